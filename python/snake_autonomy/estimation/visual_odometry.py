"""Frame-to-keyframe visual odometry from colour (or grey) and depth images, ROS-free.

    vo = VisualOdometry(K, load_vo_params("config/estimation.yaml"))
    result = vo.process(image, depth_m, stamp_s)
    result.T_odom_camera (4x4), result.covariance (6x6), result.inliers, result.state ("ok" | "lost"),
    result.reason (why it is lost), result.keyframe (True when this frame became the keyframe)

The design of RTAB-Map's frame-to-keyframe odometry: ORB features of the keyframe carry a 3D point
each (its depth pixel back-projected; features on a depth hole, 0 or NaN, or outside the depth range
are dropped); every new frame's ORB features are matched to them (Hamming distance, Lowe's ratio
test) and the camera's pose relative to the keyframe is PnP-RANSAC (OpenCV) on those 3D-2D matches,
EPnP in the RANSAC loop, refined by Levenberg-Marquardt on the inliers; then, as ORB-SLAM's RGB-D
tracking does, each inlier's depth measured in the current frame enters a Gauss-Newton refinement
as the difference of its measured and predicted inverse depth (std depth_inverse_sigma_per_m, Huber
at depth_gate_sigmas), the matches classified again, at most four times. The current frame replaces
the keyframe when the inliers fall below keyframe_min_inliers or below keyframe_min_overlap of the
keyframe's 3D points, unless one of the last keyframe_memory keyframes places it with enough
inliers: that one is the keyframe again (a view seen before adds no new keyframe error); when a
frame cannot be placed against the keyframe (its view is gone at once: a fast turn), the last
tracked frame becomes the keyframe and the frame is tried against it.

Frames: the camera frame is OpenCV's optical frame (x right, y down, z forward); the odometry frame
is the first keyframe's camera frame unless an initial pose is given.

Tracking is lost (state "lost", the pose held at the last good one, covariance LOST_COVARIANCE on
the diagonal: RTAB-Map's null-pose convention, which the pose remapper refuses) when a frame has too
few features, matches or inliers, or the pose moved from the last good one by more than
max_step_m / max_step_deg (a gross PnP error). While lost, every frame is tried against the
keyframe again: tracking resumes when the camera sees the keyframe's scene again.

Covariance (x, y, z, then small rotations about the odometry frame's fixed x, y, z axes, as in
geometry_msgs/PoseWithCovariance): the Gauss-Newton covariance of the PnP fit,
(sum_i J_i^T W_i J_i)^-1, J_i an inlier's reprojection Jacobian with respect to the camera's pose
and W_i the inverse of its image-space covariance, min_pixel_sigma_px^2 I (the keyframe's points
taken as exact), plus each inlier's inverse depth (std depth_inverse_sigma_per_m) when the depth is
in the fit; scaled by the fit's variance factor (the residuals' chi^2 per degree of freedom) when above 1. Added
to the keyframe's covariance carried over the lever arm from the keyframe to the camera, so
covariance grows with each keyframe change, as odometry drift does. The first keyframe's pose is the
odometry frame's origin, with zero covariance. Each tracked result names the keyframe it was
measured against (keyframe_stamp, T_odom_keyframe).
"""
import math
from collections import deque
from dataclasses import dataclass, field, fields
from typing import Deque, List, Optional

import cv2
import numpy as np
from scipy.spatial.distance import cdist

from .config_section import load_section
from .pose_remap import skew

OK = "ok"
LOST = "lost"
#: the diagonal of a lost pose's covariance (RTAB-Map's null pose)
LOST_COVARIANCE = 9999.0


@dataclass
class VoParams:
    """The vo: section of config/estimation.yaml."""
    n_features: int = 600              # ORB features per frame
    scale_factor: float = 1.2          # ORB pyramid scale between levels
    n_levels: int = 4                  # ORB pyramid levels
    fast_threshold: int = 12           # FAST corner threshold (grey levels)
    edge_threshold_px: int = 19        # border without features (also ORB's patch size)
    ratio_test: float = 0.8            # a match's Hamming distance below this x the second best's
    max_hamming: int = 64              # and at most this many bits
    min_depth_m: float = 0.1           # keyframe features with depth outside this range have no 3D point
    max_depth_m: float = 4.0
    ransac_reprojection_px: float = 2.0   # PnP-RANSAC inlier threshold
    ransac_iterations: int = 100
    ransac_confidence: float = 0.99
    min_inliers: int = 20              # fewer: lost
    # every keyframe change adds the relative pose's error: switching late keeps drift down (on
    # simulator renders, switching below 0.3 overlap, i.e. nearly every frame, drifted several times more)
    keyframe_min_inliers: int = 50     # fewer: the frame becomes the keyframe
    keyframe_min_overlap: float = 0.1  # inliers over the keyframe's 3D points below this: new keyframe
    max_step_m: float = 0.3            # a pose further than this from the last good one: lost (gross error)
    max_step_deg: float = 45.0
    min_pixel_sigma_px: float = 1.0    # the covariance's reprojection std is at least this
    # earlier keyframes kept: when the keyframe's inliers drop, the one of them with the most inliers
    # (at least keyframe_min_inliers) becomes the keyframe again before the frame becomes a new one
    # (0: none); the head yawing back and forth while sidewinding sees them again
    keyframe_memory: int = 4
    guided_radius_px: float = 30.0     # with a predicted pose: a keyframe point matches only features within
                                       # this of where the prediction projects it (0: every feature)
    depth_redetect_below: int = 50     # a frame with fewer features with depth than this is detected again
                                       # within the pixels that have depth (0: never); a far wall's strong
                                       # texture beyond max_depth_m took every feature
    # the frame's own depth in the fit (ORB-SLAM's RGB-D tracking): each inlier with depth adds the
    # difference of its measured and its predicted inverse depth, with this std (1/m; 0: the 2D fit
    # alone); the D435i-like depth noise, std 0.0052 z^2 m, is 0.0052 1/m in inverse depth, and half a
    # pixel's rounding on the grazing floor adds as much again
    depth_inverse_sigma_per_m: float = 0.01
    depth_gate_sigmas: float = 3.0     # a match whose inverse depth is further off than this many stds: outlier

    def problems(self, prefix: str = "vo") -> List[str]:
        """Every invalid value, each naming its key and value."""
        out = []
        for f in fields(self):
            v, (kind, low, high) = getattr(self, f.name), _LIMITS[f.name]
            integer = isinstance(v, int) and not isinstance(v, bool)
            number = integer or (isinstance(v, float) and math.isfinite(v))
            if (kind is int and not integer) or not number or not low <= v <= high:
                what = "an integer" if kind is int else "a finite number"
                out.append(f"{prefix}.{f.name}: must be {what} in [{low:g}, {high:g}], got {v!r}")
        if not out and self.min_depth_m >= self.max_depth_m:
            out.append(f"{prefix}.min_depth_m: must be below max_depth_m ({self.max_depth_m:g}), "
                       f"got {self.min_depth_m!r}")
        if not out and self.keyframe_min_inliers < self.min_inliers:
            out.append(f"{prefix}.keyframe_min_inliers: must be at least min_inliers ({self.min_inliers}), "
                       f"got {self.keyframe_min_inliers!r}")
        return out


#: (type, lowest, highest) of every VoParams field
_LIMITS = {
    "n_features": (int, 50, 20000), "scale_factor": (float, 1.01, 2.0), "n_levels": (int, 1, 16),
    "fast_threshold": (int, 1, 255), "edge_threshold_px": (int, 3, 64), "ratio_test": (float, 0.1, 1.0),
    "max_hamming": (int, 1, 256), "min_depth_m": (float, 0.0, 100.0), "max_depth_m": (float, 0.01, 100.0),
    "ransac_reprojection_px": (float, 0.1, 50.0), "ransac_iterations": (int, 10, 10000),
    "ransac_confidence": (float, 0.5, 0.99999), "min_inliers": (int, 6, 10000),
    "keyframe_min_inliers": (int, 6, 10000), "keyframe_min_overlap": (float, 0.0, 1.0),
    "max_step_m": (float, 1e-3, 100.0), "max_step_deg": (float, 0.1, 180.0),
    "min_pixel_sigma_px": (float, 0.0, 100.0), "guided_radius_px": (float, 0.0, 10000.0),
    "keyframe_memory": (int, 0, 100),
    "depth_redetect_below": (int, 0, 20000), "depth_inverse_sigma_per_m": (float, 0.0, 10.0),
    "depth_gate_sigmas": (float, 0.5, 100.0),
}
assert set(_LIMITS) == {f.name for f in fields(VoParams)}


def load_vo_params(path) -> VoParams:
    """The vo: section of an estimation config (absent: defaults). ValueError naming the file, the
    field and the value for an unknown key or an invalid value."""
    return load_section(path, "vo", VoParams)


@dataclass
class VoResult:
    stamp: float
    T_odom_camera: np.ndarray          # 4x4, the camera's optical frame in the odometry frame
    covariance: np.ndarray             # 6x6 (x, y, z, rx, ry, rz); LOST_COVARIANCE diagonal when lost
    state: str                         # OK or LOST
    reason: str = ""                   # why it is lost ("" when ok)
    inliers: int = 0                   # PnP inliers (a new first keyframe: its 3D points)
    matches: int = 0                   # ratio-test matches to the keyframe
    features: int = 0                  # ORB features in the frame
    keyframe: bool = False             # the frame became the keyframe
    #: the PnP fit's own covariance against the keyframe (the keyframe's not added; same axes): the
    #: error of the motion since the keyframe; zero for a first keyframe, None when lost
    relative_covariance: Optional[np.ndarray] = None
    #: the keyframe the pose was measured against: its stamp and its camera pose in the odometry
    #: frame (None when lost or for a first keyframe)
    keyframe_stamp: Optional[float] = None
    T_odom_keyframe: Optional[np.ndarray] = None

    @property
    def ok(self) -> bool:
        return self.state == OK


@dataclass
class _Keyframe:
    T_odom_camera: np.ndarray
    covariance: np.ndarray
    points: np.ndarray                 # (N, 3) in the keyframe's camera frame
    descriptors: np.ndarray            # (N, 32) uint8
    stamp: float


@dataclass
class _Features:
    uv: np.ndarray                     # (N, 2) pixel coordinates of every feature
    descriptors: Optional[np.ndarray]  # (N, 32) uint8 or None
    depth: np.ndarray = field(default_factory=lambda: np.zeros(0))   # (N,) m; 0 where none usable


def rotation_angle_deg(R: np.ndarray) -> float:
    c = (float(np.trace(R)) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


_POPCOUNT = np.array([bin(i).count("1") for i in range(256)], np.uint16)


def _knn_allowed(kf_desc: np.ndarray, desc: np.ndarray, allowed: np.ndarray):
    """knnMatch(k=2) restricted to the allowed (keyframe, frame) pairs, as (keyframe index, frame
    index, best distance, second distance or None) per keyframe point with a candidate: only the
    allowed pairs' Hamming distances are computed (OpenCV's masked knnMatch took 18 ms a frame)."""
    q, t = np.nonzero(allowed)
    if len(q) == 0:
        return []
    d = _POPCOUNT[np.bitwise_xor(kf_desc[q], desc[t])].sum(axis=1)
    order = np.lexsort((d, q))                      # by keyframe point, then distance
    q, t, d = q[order], t[order], d[order]
    starts = np.nonzero(np.r_[True, q[1:] != q[:-1]])[0]
    has_second = np.r_[starts[1:] - starts[:-1] > 1, len(q) - starts[-1] > 1]
    return [(int(q[i]), int(t[i]), float(d[i]), float(d[i + 1]) if two else None)
            for i, two in zip(starts, has_second)]


class VisualOdometry:
    """ORB + depth + PnP-RANSAC against a keyframe (see the module's docstring)."""

    def __init__(self, K, params: Optional[VoParams] = None, initial_pose: Optional[np.ndarray] = None):
        K = np.asarray(K, float)
        if K.shape != (3, 3) or not np.all(np.isfinite(K)) or K[0, 0] <= 0 or K[1, 1] <= 0:
            raise ValueError(f"K: expected a 3x3 camera matrix with fx, fy > 0, got {K.tolist()}")
        self.K = K
        self.params = params or VoParams()
        problems = self.params.problems()
        if problems:
            raise ValueError("visual odometry: " + "; ".join(problems))
        p = self.params
        self._orb = cv2.ORB_create(nfeatures=p.n_features, scaleFactor=p.scale_factor, nlevels=p.n_levels,
                                   edgeThreshold=p.edge_threshold_px, patchSize=p.edge_threshold_px,
                                   fastThreshold=p.fast_threshold)
        self._matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
        self.reset(initial_pose)

    def reset(self, T_odom_camera: Optional[np.ndarray] = None, covariance: Optional[np.ndarray] = None) -> None:
        """Forget the keyframe: the next frame with enough 3D features becomes the keyframe, at
        T_odom_camera (default: the identity) with this covariance (default: zero)."""
        self._pose = np.eye(4) if T_odom_camera is None else np.array(T_odom_camera, float)
        self._covariance = np.zeros((6, 6)) if covariance is None else np.array(covariance, float)
        self._keyframe: Optional[_Keyframe] = None
        self._earlier: Deque[_Keyframe] = deque(maxlen=max(self.params.keyframe_memory, 1))   # older keyframes
        self._previous: Optional[_Features] = None   # the last tracked frame's features, unless the keyframe
        self._previous_stamp = 0.0
        self.keyframes = 0             # keyframes taken since the reset

    @property
    def pose(self) -> np.ndarray:
        """The last good camera pose in the odometry frame."""
        return self._pose.copy()

    # ---------------------------------------------------------------------------------------------
    def process(self, image, depth_m, stamp: float, mask=None, predicted=None) -> VoResult:
        """One frame: image (H, W) grey or (H, W, 3) RGB uint8, depth_m (H, W) metres along the
        optical axis (0 or NaN: no depth), stamp in seconds; mask (H, W), optional: features only
        where it is non-zero (e.g. not on the robot's own body, which moves with the camera);
        predicted (4x4, optional): the camera's pose expected now (e.g. from the IMU): with
        guided_radius_px > 0 a keyframe point is matched only to features near its projection there."""
        feats = self._features(image, depth_m, mask)
        if self._keyframe is None:
            return self._first_keyframe(feats, stamp)
        result = self._track(feats, stamp, predicted)
        previous, self._previous = self._previous, None
        previous_stamp = self._previous_stamp
        if not result.ok and previous is not None and result.features >= self.params.min_inliers:
            # the keyframe's view is gone: the last tracked frame (at the last good pose) becomes
            # the keyframe and the frame is tried against it
            if self._set_keyframe(previous, previous_stamp):
                retry = self._track(feats, stamp, predicted)
                result = retry if retry.ok else result
        if result.ok and not result.keyframe:
            self._previous, self._previous_stamp = feats, stamp
        return result

    def _track(self, feats: "_Features", stamp: float, predicted=None) -> VoResult:
        """The frame's pose against the keyframe; when its inliers drop, against the earlier keyframe
        (the last keyframe_memory) with the most inliers, if one has enough, which becomes the
        keyframe again; else the frame becomes the keyframe. Lost when none places it."""
        kf = self._keyframe
        placed = self._place(kf, feats, stamp, predicted)
        if self._earlier and self._degraded(placed, kf):
            best = None
            for old in reversed(self._earlier):
                other = self._place(old, feats, stamp, predicted)
                if not self._degraded(other, old) and (best is None or other[3] > best[1][3]):
                    best = (old, other)
            if best is not None:        # the view came back: its keyframe's error, not a new one's
                kept = [k for k in self._earlier if k is not best[0]] + [kf]
                self._earlier = deque(kept, maxlen=self._earlier.maxlen)
                kf, placed = best
                self._keyframe = kf
        if isinstance(placed, VoResult):
            return placed
        T, cov, rel, n_inliers, n_matches = placed
        self._pose, self._covariance = T, cov
        new_kf = self._degraded(placed, kf) and self._set_keyframe(feats, stamp)
        return VoResult(stamp, T.copy(), cov.copy(), OK, "", n_inliers, n_matches, len(feats.uv), new_kf, rel,
                        kf.stamp, kf.T_odom_camera.copy())

    def _degraded(self, placed, kf: "_Keyframe") -> bool:
        """Lost against kf, or too few inliers (keyframe_min_inliers, keyframe_min_overlap) to keep it."""
        if isinstance(placed, VoResult):
            return True
        p = self.params
        return placed[3] < p.keyframe_min_inliers or placed[3] < p.keyframe_min_overlap * len(kf.points)

    def _place(self, kf: "_Keyframe", feats: "_Features", stamp: float, predicted=None):
        """(pose, its covariance, the PnP fit's covariance, inliers, matches) of the frame against kf,
        or a lost VoResult saying why not."""
        p = self.params
        n_feat = len(feats.uv)
        if feats.descriptors is None or n_feat < p.min_inliers:
            return self._lost(stamp, f"too few features: {n_feat} (min_inliers {p.min_inliers})", features=n_feat)
        kf_idx, cur_idx = self._match(kf.descriptors, feats.descriptors, self._guide(kf, feats, predicted))
        if len(kf_idx) < p.min_inliers:
            return self._lost(stamp, f"too few matches to the keyframe: {len(kf_idx)} (min_inliers "
                                     f"{p.min_inliers})", features=n_feat, matches=len(kf_idx))
        obj = kf.points[kf_idx]
        img = feats.uv[cur_idx]
        depth = feats.depth[cur_idx]
        solved = self._solve_pnp(obj, img, depth)
        if solved is None:
            return self._lost(stamp, "PnP-RANSAC found no pose", features=n_feat, matches=len(kf_idx))
        rvec, tvec, inl = solved
        if len(inl) < p.min_inliers:
            return self._lost(stamp, f"too few inliers: {len(inl)} (min_inliers {p.min_inliers})",
                              features=n_feat, matches=len(kf_idx), inliers=len(inl))
        R_cam_kf, _ = cv2.Rodrigues(rvec)
        T_kf_cam = np.eye(4)
        T_kf_cam[:3, :3] = R_cam_kf.T
        T_kf_cam[:3, 3] = -R_cam_kf.T @ tvec.ravel()
        T = kf.T_odom_camera @ T_kf_cam
        step_m = float(np.linalg.norm(T[:3, 3] - self._pose[:3, 3]))
        step_deg = rotation_angle_deg(self._pose[:3, :3].T @ T[:3, :3])
        if step_m > p.max_step_m or step_deg > p.max_step_deg:
            return self._lost(stamp, f"pose jumped {step_m:.3f} m, {step_deg:.1f} deg from the last good one "
                                     f"(max_step_m {p.max_step_m:g}, max_step_deg {p.max_step_deg:g})",
                              features=n_feat, matches=len(kf_idx), inliers=len(inl))
        cov, rel = self._covariance_of(T, kf, obj[inl], img[inl], rvec, tvec, depth[inl])
        return T, cov, rel, len(inl), len(kf_idx)

    # ---------------------------------------------------------------------------------------------
    def _features(self, image, depth_m, mask=None) -> _Features:
        img = np.asarray(image)
        grey = cv2.cvtColor(img, cv2.COLOR_RGB2GRAY) if img.ndim == 3 else img
        if grey.dtype != np.uint8:
            raise ValueError(f"image: expected uint8, got {grey.dtype}")
        depth = np.asarray(depth_m, np.float32)
        if depth.shape != grey.shape:
            raise ValueError(f"depth_m: shape {depth.shape} differs from the image's {grey.shape}")
        if mask is not None:
            mask = np.asarray(mask)
            if mask.shape != grey.shape:
                raise ValueError(f"mask: shape {mask.shape} differs from the image's {grey.shape}")
            mask = (mask != 0).astype(np.uint8)
        feats = self._detect(grey, depth, mask)
        if int(np.count_nonzero(feats.depth > 0)) < self.params.depth_redetect_below:
            # ORB's strongest corners lie where there is no depth (a textured wall beyond max_depth_m):
            # detect again where there is, and keep whichever set has more 3D points
            with_depth = self._usable(depth).astype(np.uint8)
            again = self._detect(grey, depth, with_depth if mask is None else with_depth & mask)
            if np.count_nonzero(again.depth > 0) > np.count_nonzero(feats.depth > 0):
                feats = again
        return feats

    def _usable(self, z: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            return np.isfinite(z) & (z >= self.params.min_depth_m) & (z <= self.params.max_depth_m)

    def _detect(self, grey, depth, mask) -> _Features:
        kps, desc = self._orb.detectAndCompute(grey, mask)
        uv = np.array([k.pt for k in kps], np.float64).reshape(-1, 2)
        if len(uv) == 0:
            return _Features(uv, None)
        col = np.clip(np.rint(uv[:, 0]).astype(int), 0, depth.shape[1] - 1)
        row = np.clip(np.rint(uv[:, 1]).astype(int), 0, depth.shape[0] - 1)
        z = depth[row, col].astype(np.float64)
        return _Features(uv, desc, np.where(self._usable(z), z, 0.0))

    def _first_keyframe(self, feats: _Features, stamp: float) -> VoResult:
        n_3d = int(np.count_nonzero(feats.depth > 0))
        if n_3d < self.params.min_inliers:
            return self._lost(stamp, f"no keyframe yet: {n_3d} features with depth (min_inliers "
                                     f"{self.params.min_inliers})", features=len(feats.uv))
        self._set_keyframe(feats, stamp)
        return VoResult(stamp, self._pose.copy(), self._covariance.copy(), OK, "", n_3d, 0, len(feats.uv), True,
                        np.zeros((6, 6)))

    def _set_keyframe(self, feats: _Features, stamp: float) -> bool:
        """The frame becomes the keyframe at the present pose when it has enough 3D features."""
        has = feats.depth > 0
        if int(np.count_nonzero(has)) < self.params.min_inliers:
            return False
        K, z = self.K, feats.depth[has]
        uv = feats.uv[has]
        pts = np.column_stack([(uv[:, 0] - K[0, 2]) * z / K[0, 0], (uv[:, 1] - K[1, 2]) * z / K[1, 1], z])
        if self._keyframe is not None and self.params.keyframe_memory > 0:
            self._earlier.append(self._keyframe)
        self._keyframe = _Keyframe(self._pose.copy(), self._covariance.copy(), pts,
                                   feats.descriptors[has], stamp)
        self.keyframes += 1
        return True

    def _guide(self, kf: "_Keyframe", feats: "_Features", predicted) -> Optional[np.ndarray]:
        """(keyframe points, features) bool: true where the feature lies within guided_radius_px of
        the point's projection at the predicted pose (None: no prediction, or guiding off)."""
        r = self.params.guided_radius_px
        if predicted is None or r <= 0:
            return None
        T_cam_kf = np.linalg.inv(np.asarray(predicted, float)) @ kf.T_odom_camera
        rvec, tvec = cv2.Rodrigues(T_cam_kf[:3, :3])[0], T_cam_kf[:3, 3]
        in_front = kf.points @ T_cam_kf[2, :3] + T_cam_kf[2, 3] > 1e-6     # depth at the predicted pose
        uv = self._project(kf.points, rvec, tvec)
        return (cdist(uv, feats.uv, "sqeuclidean") <= r * r) & in_front[:, None]

    def _match(self, kf_desc: np.ndarray, desc: np.ndarray, allowed: Optional[np.ndarray] = None):
        """Indices (keyframe, frame) of the matches passing the ratio test and max_hamming (only
        the pairs allowed, when given)."""
        p = self.params
        if allowed is None:
            pairs = [(m[0].queryIdx, m[0].trainIdx, m[0].distance, m[1].distance if len(m) > 1 else None)
                     for m in self._matcher.knnMatch(kf_desc, desc, k=2) if m]
        else:
            pairs = _knn_allowed(kf_desc, desc, allowed)
        kf_idx, cur_idx, used = [], [], set()
        for query, train, best, second in pairs:
            if best > p.max_hamming or (second is not None and best >= p.ratio_test * second):
                continue
            if train in used:              # one keyframe point per image feature
                continue
            used.add(train)
            kf_idx.append(query)
            cur_idx.append(train)
        return np.array(kf_idx, int), np.array(cur_idx, int)

    def _solve_pnp(self, obj: np.ndarray, img: np.ndarray, depth: Optional[np.ndarray] = None):
        """(rvec, tvec, inlier indices) of the keyframe in the camera, or None. depth (N,): the
        frame's measured depth at each match (0: none); with depth_inverse_sigma_per_m > 0 the pose
        is refined on it as well and a match whose depth disagrees is an outlier."""
        p = self.params
        ok, rvec, tvec, inliers = cv2.solvePnPRansac(
            obj, img, self.K, None, iterationsCount=p.ransac_iterations,
            reprojectionError=p.ransac_reprojection_px, confidence=p.ransac_confidence,
            flags=cv2.SOLVEPNP_EPNP)
        if not ok or inliers is None or len(inliers) < 6:
            return None
        inl = inliers.ravel()
        rvec, tvec = cv2.solvePnPRefineLM(obj[inl], img[inl], self.K, None, rvec, tvec)
        # the refined pose's inliers (the refinement can move points across the threshold)
        inl = self._inliers(obj, img, None, rvec, tvec)
        if depth is None or p.depth_inverse_sigma_per_m <= 0:
            return rvec, tvec, inl
        # ORB-SLAM's pose optimisation: fit, classify the matches again, at most four times; the
        # 2D fit's translation along the view is weak (far points), so the first fit with depth is
        # on the 2D inliers, before any of them is judged by its depth
        for _ in range(4):
            if len(inl) < 6:
                break
            rvec, tvec = self._refine_with_depth(obj[inl], img[inl], depth[inl], rvec, tvec)
            again = self._inliers(obj, img, depth, rvec, tvec)
            if np.array_equal(again, inl):
                break
            inl = again
        return rvec, tvec, inl

    def _inliers(self, obj, img, depth, rvec, tvec) -> np.ndarray:
        """Indices of the matches within ransac_reprojection_px and, given depth, whose inverse
        depth is within depth_gate_sigmas stds of the predicted one (those without depth pass)."""
        p = self.params
        r = self._residuals(obj, img, rvec, tvec)
        good = np.hypot(r[:, 0], r[:, 1]) <= p.ransac_reprojection_px
        if depth is not None:
            z = obj @ cv2.Rodrigues(rvec)[0][2] + float(np.ravel(tvec)[2])
            with np.errstate(divide="ignore", invalid="ignore"):
                off = np.abs(1.0 / depth - 1.0 / np.where(z > 1e-6, z, np.nan))
            good &= (depth <= 0) | (off <= p.depth_gate_sigmas * p.depth_inverse_sigma_per_m)
        return np.nonzero(good)[0]

    def _refine_with_depth(self, obj, img, depth, rvec, tvec, iterations: int = 10):
        """rvec, tvec minimising the reprojection errors (std min_pixel_sigma_px) and, for the
        points with depth, the differences of measured and predicted inverse depth (std
        depth_inverse_sigma_per_m), each point's whitened 2D error and its inverse depth's under a
        Huber loss at depth_gate_sigmas (ORB-SLAM's robust kernel: one wrong depth must not drag
        the fit): iteratively reweighted Gauss-Newton on x_c -> x_c + v + w x x_c (the points in
        the camera), a step kept only when it lowers the loss."""
        p, K = self.params, self.K
        R, t = cv2.Rodrigues(rvec)[0], np.ravel(tvec).astype(np.float64)
        w_px, w_d = 1.0 / max(p.min_pixel_sigma_px, 1e-3), 1.0 / p.depth_inverse_sigma_per_m
        delta = p.depth_gate_sigmas
        has = depth > 0
        inv_zm = 1.0 / depth[has]

        def whitened(R, t):
            """the points in the camera, their depths, whitened 2D errors (N, 2) and inverse depth errors"""
            x = obj @ R.T + t
            z = np.maximum(x[:, 2], 1e-6)
            uv = np.column_stack([K[0, 0] * x[:, 0] / z + K[0, 2], K[1, 1] * x[:, 1] / z + K[1, 2]])
            return x, z, w_px * (uv - img), w_d * (1.0 / z[has] - inv_zm)

        def loss(e_uv, e_d):
            s = np.concatenate([np.hypot(e_uv[:, 0], e_uv[:, 1]), np.abs(e_d)])
            return float(np.sum(np.where(s <= delta, s * s, 2 * delta * s - delta * delta)))

        x, z, e_uv, e_d = whitened(R, t)
        cost = loss(e_uv, e_d)
        for _ in range(iterations):
            # gradients of u, v and 1/z with respect to x_c; with respect to w: x_c x gradient
            gu = np.column_stack([K[0, 0] / z, np.zeros_like(z), -K[0, 0] * x[:, 0] / z ** 2])
            gv = np.column_stack([np.zeros_like(z), K[1, 1] / z, -K[1, 1] * x[:, 1] / z ** 2])
            gd = np.zeros((len(e_d), 3))
            gd[:, 2] = -1.0 / z[has] ** 2
            # Huber's weights (square roots) per point's 2D error and per inverse depth
            s_uv = np.hypot(e_uv[:, 0], e_uv[:, 1])
            r_uv = np.sqrt(np.minimum(1.0, delta / np.maximum(s_uv, 1e-12)))
            r_d = np.sqrt(np.minimum(1.0, delta / np.maximum(np.abs(e_d), 1e-12)))
            J = np.vstack([np.column_stack([gu, np.cross(x, gu)]) * (w_px * r_uv)[:, None],
                           np.column_stack([gv, np.cross(x, gv)]) * (w_px * r_uv)[:, None],
                           np.column_stack([gd, np.cross(x[has], gd)]) * (w_d * r_d)[:, None]])
            e = np.concatenate([e_uv[:, 0] * r_uv, e_uv[:, 1] * r_uv, e_d * r_d])
            try:
                step = -np.linalg.solve(J.T @ J, J.T @ e)
            except np.linalg.LinAlgError:
                break
            dR = cv2.Rodrigues(step[3:])[0]
            R_new, t_new = dR @ R, dR @ t + step[:3]
            x_new, z_new, e_uv_new, e_d_new = whitened(R_new, t_new)
            cost_new = loss(e_uv_new, e_d_new)
            if cost_new >= cost:
                break
            R, t, x, z, e_uv, e_d, cost = R_new, t_new, x_new, z_new, e_uv_new, e_d_new, cost_new
            if np.linalg.norm(step) < 1e-9:
                break
        return cv2.Rodrigues(R)[0], t.reshape(3, 1)

    def _project(self, obj, rvec, tvec) -> np.ndarray:
        """(N, 2) pixels of the points obj (N, 3) seen from the pose rvec, tvec (OpenCV's)."""
        proj, _ = cv2.projectPoints(np.asarray(obj, np.float64), rvec, np.asarray(tvec, np.float64), self.K, None)
        return proj.reshape(-1, 2)

    def _residuals(self, obj, img, rvec, tvec) -> np.ndarray:
        return self._project(obj, rvec, tvec) - img

    def _covariance_of(self, T: np.ndarray, kf: _Keyframe, obj, img, rvec, tvec, depth=None):
        """The pose's covariance (see the module's docstring) and the PnP fit's part of it; depth
        (the inliers' measured depth, 0: none) adds each one's inverse depth when it is in the fit."""
        K, R, p_cam = self.K, T[:3, :3], T[:3, 3]
        r = self._residuals(obj, img, rvec, tvec)
        n = len(obj)
        X_w = obj @ kf.T_odom_camera[:3, :3].T + kf.T_odom_camera[:3, 3]
        d = X_w - p_cam
        x_c = d @ R                                     # R^T d, the points in the camera
        z = x_c[:, 2]
        # d(u, v)/d(x_c): (N, 2, 3)
        Ju = np.zeros((n, 2, 3))
        Ju[:, 0, 0] = K[0, 0] / z
        Ju[:, 0, 2] = -K[0, 0] * x_c[:, 0] / z ** 2
        Ju[:, 1, 1] = K[1, 1] / z
        Ju[:, 1, 2] = -K[1, 1] * x_c[:, 1] / z ** 2
        # x_c = R^T (X_w - p): d x_c / d p = -R^T; for R = Exp(phi) R_hat, d x_c / d phi = R^T [d]x
        J_pose = np.zeros((n, 3, 6))
        J_pose[:, :, :3] = -R.T
        skews = np.zeros((n, 3, 3))
        skews[:, 0, 1], skews[:, 0, 2], skews[:, 1, 2] = -d[:, 2], d[:, 1], -d[:, 0]
        skews[:, 1, 0], skews[:, 2, 0], skews[:, 2, 1] = d[:, 2], -d[:, 1], d[:, 0]
        J_pose[:, :, 3:] = R.T @ skews
        J = Ju @ J_pose                                 # (N, 2, 6)
        # each point's image-space information: the inverse of the pixel noise's variance
        px2 = self.params.min_pixel_sigma_px ** 2
        W = np.broadcast_to(np.eye(2) / max(px2, 1e-12), (n, 2, 2))
        info = np.einsum("nai,nab,nbj->ij", J, W, J)
        # the fit's variance factor (its normalised residuals' chi^2 per degree of freedom), at least 1
        chi2 = float(np.einsum("na,nab,nb->", r, W, r))
        n_rows = 2 * n
        if depth is not None and self.params.depth_inverse_sigma_per_m > 0:
            has = depth > 0
            J_d = -J_pose[has, 2, :] / z[has, None] ** 2     # d(1/z)/d pose
            w_d = self.params.depth_inverse_sigma_per_m ** -2
            r_d = 1.0 / z[has] - 1.0 / depth[has]
            info = info + w_d * J_d.T @ J_d
            chi2 += w_d * float(r_d @ r_d)
            n_rows += int(np.count_nonzero(has))
        scale = max(chi2 / max(n_rows - 6, 1), 1.0)
        try:
            rel = scale * np.linalg.inv(info)
        except np.linalg.LinAlgError:
            rel = np.eye(6) * LOST_COVARIANCE
        A = np.eye(6)
        A[:3, 3:] = -skew(p_cam - kf.T_odom_camera[:3, 3])
        cov = A @ kf.covariance @ A.T + rel
        return 0.5 * (cov + cov.T), 0.5 * (rel + rel.T)

    def _lost(self, stamp: float, reason: str, features: int = 0, matches: int = 0, inliers: int = 0) -> VoResult:
        return VoResult(stamp, self._pose.copy(), np.eye(6) * LOST_COVARIANCE, LOST, reason, inliers, matches,
                        features, False)
