"""Perception-space collision checks (Chang et al. III): a path's poses, a footprint at each
projected into the current traversability image; free while every projected pixel is ground.

The ground frame: the robot's current pose on the floor (x forward, y left, z up, origin under
base_link). T_ground_camera: the camera's optical frame in it (OpenCV: x right, y down, z forward).
The footprint at a pose is the segment across the path, width footprint width (the head's 51 mm on
Chang's robot; the planner passes the body's swept width, planner.py), sampled at points no further
apart than point_spacing_m and at least `footprint_points` (a line, as in the paper: the image is a
homography of the floor, so only the footprint on the floor is hallucinated).

A point the current image shows is judged by it, however near. A point the image does not show
(below the bottom row, beside or beyond the field of view) is looked up in the earlier views given
with add_view (the last few replans' images, each with its camera pose in the current ground frame;
images, not a map: nothing is fused): free when one of them shows it as ground, or, with
blocked_wins (config/nav.yaml), when some show it as ground and none as an obstacle (the
monocular classifier misses a cylinder in one view and not in the next: the miss must not free
it); with blocked_wins_depth_m only an obstacle's face wins so, not the shadow behind
it (an old view's shadow blocked the floor beside the head that every later view showed). Seen in
none, it counts as free when nearer (ahead of the camera, along its heading on the floor) than
near_field_m, the distance at which the view becomes as wide as the footprint (or the
bottom row's, if further): the robot is there or came from there; anywhere else it is not known to
be free. Without the earlier views a passed obstacle beside the body is free (the head slid
along the cylinder it had passed).
"""
import math
from typing import Optional

import numpy as np


class _View:
    """One traversability image and the projection of ground points into it."""

    def __init__(self, K, ground: np.ndarray, T_ground_camera: np.ndarray, max_depth_m: float = math.inf,
                 obstacle_depth_m: float = math.inf, face_depth_m: float = math.inf):
        self.max_depth_m = max_depth_m
        T_cam_ground = np.linalg.inv(np.asarray(T_ground_camera, float))
        self.R, self.t = T_cam_ground[:3, :3], T_cam_ground[:3, 3]
        self.K, self.ground = K, ground
        self.edge_depth = self.face_depth = None
        face_depth_m = min(face_depth_m, obstacle_depth_m)
        if math.isfinite(face_depth_m):
            # per column, the depth of the floor at the ground region's top edge (the region is
            # grown from the bottom): non-ground further than obstacle_depth_m beyond it is hidden
            # behind the obstacle there, not known to be one; up to face_depth_m it is the face
            h, w = ground.shape
            top = np.where(ground.any(axis=0), np.argmax(ground, axis=0), h) - 0.5
            _, depth, _ = floor_rays(np.arange(w), top, K, T_ground_camera)
            self.edge_depth = depth + obstacle_depth_m
            self.face_depth = depth + face_depth_m

    def look(self, pts: np.ndarray, faces: bool = False):
        """(M, 3) ground points -> (shown (M,) bool, ground (M,) bool where shown); faces: and (M,)
        bool, shown as an obstacle within face_depth_m of the ground region's edge (the face, not
        the shadow behind it)."""
        c = pts @ self.R.T + self.t
        z = c[:, 2]
        zs = np.where(z > 1e-9, z, 1.0)
        u = np.round(self.K[0, 0] * c[:, 0] / zs + self.K[0, 2]).astype(np.int64)
        v = np.round(self.K[1, 1] * c[:, 1] / zs + self.K[1, 2]).astype(np.int64)
        h, w = self.ground.shape
        shown = (z > 1e-9) & (z < self.max_depth_m) & (u >= 0) & (u < w) & (v >= 0) & (v < h)
        free = np.zeros(len(pts), bool)
        free[shown] = self.ground[v[shown], u[shown]]
        if self.edge_depth is not None:
            idx = np.flatnonzero(shown & ~free)
            shown[idx[z[idx] > self.edge_depth[u[idx]]]] = False
        if not faces:
            return shown, free
        face = shown & ~free
        if self.face_depth is not None:
            idx = np.flatnonzero(face)
            face[idx[z[idx] > self.face_depth[u[idx]]]] = False
        return shown, free, face


class PerceptionCollisionChecker:
    def __init__(self, intrinsics, T_ground_camera: np.ndarray, head_width_m: float,
                 footprint_points: int = 5, point_spacing_m: float = 0.04, blocked_wins: bool = False,
                 hidden_obstacles=None, blocked_wins_depth_m: float = math.inf):
        """head_width_m: the checked footprint's width (the head's, or the body's swept width).
        blocked_wins: a hidden point one earlier view shows as an obstacle is blocked whatever the
        others show (False: ground in any of them frees it). hidden_obstacles: None, or a callable
        (M, 2) ground-frame points -> (M,) bool: a point the current image does not show is blocked
        where it says so, whatever the earlier views show (obstacle_map.py). blocked_wins_depth_m: with
        blocked_wins, only non-ground within this of a view's ground edge (the obstacle's face) wins
        over ground other views show; further (the shadow behind the face, up to the view's
        obstacle_depth_m) is freed by a view showing ground there (inf: every obstacle wins)."""
        self.blocked_wins = bool(blocked_wins)
        self.blocked_wins_depth_m = float(blocked_wins_depth_m)
        self.hidden_obstacles = hidden_obstacles
        import cv2  # lazy: OpenCV is heavy and only this path needs it
        self.k = intrinsics
        self.K = intrinsics.K()
        self.dist = np.zeros(5)
        T_cam_ground = np.linalg.inv(np.asarray(T_ground_camera, float))
        self.rvec, _ = cv2.Rodrigues(T_cam_ground[:3, :3])
        self.tvec = T_cam_ground[:3, 3].copy()
        self._R, self._t = T_cam_ground[:3, :3], T_cam_ground[:3, 3]
        self._T_gc = np.asarray(T_ground_camera, float)
        self._earlier = []                                            # newest first
        # the camera's position and heading on the floor; the near field hidden under the view
        T = self._T_gc
        self._cam_xy = T[:2, 3]
        fwd = T[:2, 2] / max(1e-9, np.linalg.norm(T[:2, 2]))
        self._cam_fwd = fwd
        self.near_field_m = near_field(intrinsics, T, fwd, 0.5 * head_width_m)
        n = max(footprint_points, int(math.ceil(head_width_m / point_spacing_m - 1e-9)) + 1)
        self.width_m = float(head_width_m)
        self.offsets = np.linspace(-0.5 * head_width_m, 0.5 * head_width_m, n)

    def width_scale(self, width_m: float) -> float:
        """A footprint width as the fraction of this checker's (footprint_points' scale), at most 1."""
        return min(1.0, width_m / self.width_m)

    def add_view(self, ground: np.ndarray, T_ground_camera: np.ndarray, max_depth_m: float = math.inf,
                 obstacle_depth_m: float = math.inf) -> None:
        """An earlier traversability image, its camera in the current ground frame; add the newest
        first (a hidden point takes the value of the first view that shows it nearer than
        max_depth_m along its optical axis: the far floor is often marked unsure). Non-ground further
        than obstacle_depth_m beyond the ground region's edge in its column is not shown there
        (hidden behind the obstacle at the edge, not known to be one)."""
        self._earlier.append(_View(self.K, ground, T_ground_camera, max_depth_m, obstacle_depth_m,
                                   self.blocked_wins_depth_m))

    def footprint_points(self, poses: np.ndarray, scale: Optional[np.ndarray] = None) -> np.ndarray:
        """(N, 3) poses -> (N, P, 3) ground points of the footprint at each; scale (N,): each
        footprint's width as a fraction of the full width (None: all full)."""
        poses = np.asarray(poses, float)
        nx, ny = -np.sin(poses[:, 2]), np.cos(poses[:, 2])           # left normal
        off = self.offsets[None, :] if scale is None else np.asarray(scale, float)[:, None] * self.offsets[None, :]
        x = poses[:, 0:1] + nx[:, None] * off
        y = poses[:, 1:2] + ny[:, None] * off
        return np.dstack([x, y, np.zeros_like(x)])

    def point_free(self, flat: np.ndarray, ground: np.ndarray) -> np.ndarray:
        """(M, 3) ground points -> (M,) bool: ground in the current image where it shows them; else
        ground in any earlier view (not ground in one of them: behind an obstacle, or the obstacle);
        shown in none: free only within the near field."""
        free, known = self.point_state(flat, ground)
        unseen = np.flatnonzero(~known)
        free[unseen] = self._near(flat[unseen])
        return free

    def _near(self, flat: np.ndarray) -> np.ndarray:
        """Within the near field: nearer than near_field_m ahead of the camera on the floor (beside
        and behind it included): where the robot is or came from."""
        return (flat[:, :2] - self._cam_xy) @ self._cam_fwd < self.near_field_m

    def point_state(self, flat: np.ndarray, ground: np.ndarray):
        """(M, 3) ground points -> (free (M,), known (M,)): known where the current image or an
        earlier view shows the point; free where known and ground (as point_free judges it)."""
        shown, free = _View(self.K, ground, self._T_gc).look(flat)
        known = shown.copy()
        hidden = np.flatnonzero(~shown)
        ground_in_one = np.zeros(len(hidden), bool)
        obstacle_in_one = np.zeros(len(hidden), bool)
        face_in_one = np.zeros(len(hidden), bool)
        for view in self._earlier:
            if not len(hidden):
                break
            s, f, face = view.look(flat[hidden], faces=True)
            ground_in_one |= s & f
            obstacle_in_one |= s & ~f
            face_in_one |= face
        free[hidden] = ground_in_one & ~face_in_one if self.blocked_wins else ground_in_one
        known[hidden] = ground_in_one | obstacle_in_one
        if self.hidden_obstacles is not None and len(hidden):
            inside = hidden[np.asarray(self.hidden_obstacles(flat[hidden, :2]), bool)]
            free[inside], known[inside] = False, True
        return free, known

    def pose_state(self, poses: np.ndarray, ground: np.ndarray, scale: Optional[np.ndarray] = None):
        """(N,) bool pairs (blocked, unknown): some footprint point of the pose is known and not
        ground; none is, but some is not known and beyond the near field. scale: footprint_points."""
        pts = self.footprint_points(poses, scale)
        n, p = pts.shape[:2]
        flat = pts.reshape(-1, 3)
        free, known = self.point_state(flat, ground)
        blocked = (known & ~free).reshape(n, p).any(axis=1)
        unknown = (~known & ~self._near(flat)).reshape(n, p).any(axis=1) & ~blocked
        return blocked, unknown

    def pose_free(self, poses: np.ndarray, ground: np.ndarray) -> np.ndarray:
        """(N,) bool: every footprint point of the pose is free (point_free): neither blocked nor
        unknown (pose_state)."""
        blocked, unknown = self.pose_state(poses, ground)
        return ~blocked & ~unknown

    def free_length(self, poses: np.ndarray, ground: np.ndarray, s_m: np.ndarray) -> float:
        """Arc length s_m of the last pose of the path's collision-free prefix (0 if pose 0 is not
        free)."""
        return prefix_length(self.pose_free(poses, ground), s_m)


def floor_rays(u: np.ndarray, v: np.ndarray, K: np.ndarray, T_frame_camera: np.ndarray):
    """Pixels (u, v) -> (their rays in the frame of T_frame_camera (N, 3), each ray's parameter s at
    the floor z = 0 of that frame (inf where the ray does not go down), whether it goes down). The
    floor point is camera + s * ray."""
    T = np.asarray(T_frame_camera, float)
    rays = np.column_stack([(np.asarray(u, float) - K[0, 2]) / K[0, 0], (np.asarray(v, float) - K[1, 2]) / K[1, 1],
                            np.ones(len(u))]) @ T[:3, :3].T
    down = rays[:, 2] < -1e-9
    s = np.where(down, -T[2, 3] / np.where(down, rays[:, 2], -1.0), np.inf)
    return rays, s, down


def floor_hits(u: np.ndarray, v: np.ndarray, K: np.ndarray, T_frame_camera: np.ndarray):
    """Pixels (u, v) -> (each ray's horizontal range from the camera to the floor z = 0 of the frame, inf
    where it does not go down; the rays' unit directions on the floor (N, 2); whether each goes down).
    The floor point is the camera's (x, y) + range * direction."""
    rays, s, down = floor_rays(u, v, K, T_frame_camera)
    horiz = np.maximum(np.hypot(rays[:, 0], rays[:, 1]), 1e-9)
    return s * horiz, rays[:, :2] / horiz[:, None], down


def near_field(intrinsics, T_ground_camera: np.ndarray, fwd: np.ndarray, half_width_m: float) -> float:
    """Forward distance from the camera (along fwd on the floor) at which the image shows the floor
    at least half_width_m to both sides of the camera's heading, and below which it shows none:
    where the image's side columns (or its bottom row) meet the floor, row by row from the bottom.
    A view that never gets that wide (the camera pitched down steeply and low: its top row meets
    the floor nearer than the footprint's reach) gives the distance of the furthest floor it shows,
    not infinity: an infinite near field counted every point no view showed as free, beside the
    camera at any distance (a turn in place could then sweep into an obstacle no view showed)."""
    T = np.asarray(T_ground_camera, float)
    k = intrinsics
    v = np.arange(k.height - 1, -1, -1, dtype=float)
    best = None
    for u in (0.0, k.width - 1.0):
        rays, s, down = floor_rays(np.full_like(v, u), v, k.K(), T)
        s = np.where(down, s, 0.0)
        pts = T[:2, 3] + s[:, None] * rays[:, :2]
        d = (pts - T[:2, 3]) @ fwd
        lateral = np.abs((pts - T[:2, 3]) @ np.array([-fwd[1], fwd[0]]))
        ok = down & (lateral >= half_width_m)
        if ok.any():
            reach = float(d[np.argmax(ok)])
        else:                                   # never that wide: as far as the view shows floor
            reach = float(np.max(d[down])) if down.any() else 0.0
        best = reach if best is None else max(best, reach)
    return max(best, float(d[0]) if down[0] else 0.0)


def prefix_length(free: np.ndarray, s_m: np.ndarray) -> float:
    """s of the last pose before the first non-free one (s of the last pose if all are free)."""
    if free.all():
        return float(s_m[-1])
    return float(s_m[max(0, int(np.argmin(free)) - 1)])
