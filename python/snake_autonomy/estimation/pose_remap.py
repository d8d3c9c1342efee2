"""Camera odometry to base pose (thesis eq. 3.1, section 3.3.3), ROS-free.

    T_base^world = T_camera^world . (T_head^camera)^-1 . T_base^head                  (3.1)

with the thesis's T_a^b read as "a transform between frames a and b" and chained so that every
product is a pose in the world. In the notation of :mod:`.transforms`:

- ``camera_in_world``: the RTAB-Map odometry (nav_msgs/Odometry: pose of child_frame_id in
  header.frame_id), T_camera^world.
- ``camera_in_head``: the calibration, the camera's pose in the head frame (p_head = R p_cam + t).
  (T_head^camera)^-1 of eq. 3.1 is ``invert(camera_in_head)`` = the head's pose in the camera frame.
- ``base_in_head``: the inverse of eq. 3.3's head = base . Trans(-H, 0, 0) . Rx(+90 deg), i.e.
  ``invert(head_in_base(H))``: T_base^head of eq. 3.1.

So ``base_in_world = camera_in_world @ invert(camera_in_head) @ invert(head_in_base(H))``.
"""
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from ..safe_yaml import load_yaml_file
from ..transforms import invert, make_transform, quat_to_matrix, rot_x, rpy_to_matrix, translation

DEG = math.pi / 180.0
MAX_CAMERA_OFFSET_M = 1.0   # the camera sits on the head: an offset beyond this is a typo


def head_in_base(head_length_m: float) -> np.ndarray:
    """Eq. 3.3: the head frame in the base frame, Trans(-H, 0, 0) . Rx(+90 deg)."""
    return translation(-head_length_m, 0.0, 0.0) @ make_transform(rot_x(math.pi / 2))


class PoseRemapper:
    """Eq. 3.1 with a fixed calibration and head length."""

    def __init__(self, camera_in_head: np.ndarray, head_length_m: float):
        camera_in_head = np.asarray(camera_in_head, dtype=float)
        if camera_in_head.shape != (4, 4) or not np.all(np.isfinite(camera_in_head)):
            raise ValueError(f"camera_in_head: expected a finite 4x4 transform, got {camera_in_head!r}")
        R = camera_in_head[:3, :3]
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError(f"camera_in_head: rotation part is not a rotation matrix: {R.tolist()}")
        if not (isinstance(head_length_m, (int, float)) and math.isfinite(head_length_m) and head_length_m > 0):
            raise ValueError(f"head_length_m: must be a positive number, got {head_length_m!r}")
        self.camera_in_head = camera_in_head
        self.head_length_m = float(head_length_m)
        # the fixed right-hand factor of eq. 3.1: (T_head^camera)^-1 . T_base^head
        self.base_in_camera = invert(camera_in_head) @ invert(head_in_base(head_length_m))

    def base_in_world(self, camera_in_world: np.ndarray) -> np.ndarray:
        return np.asarray(camera_in_world, dtype=float) @ self.base_in_camera

    def head_in_world(self, camera_in_world: np.ndarray) -> np.ndarray:
        return np.asarray(camera_in_world, dtype=float) @ invert(self.camera_in_head)


@dataclass
class CameraCalibration:
    camera_in_head: np.ndarray
    calibrated: bool
    source: str


def load_camera_calibration(path) -> CameraCalibration:
    """config/camera.yaml: ``camera_in_head: {translation_m: [x, y, z], rpy_deg: [r, p, y]}`` or
    ``quaternion_xyzw: [...]`` instead of rpy_deg; ``calibrated: true|false``."""
    path = Path(path)
    data = load_yaml_file(path)
    problems = []
    section = data.get("camera_in_head") if isinstance(data, dict) else None
    if not isinstance(section, dict):
        raise ValueError(f"{path}: camera_in_head: missing or not a mapping, got {section!r}")

    def vector(key, n):
        v = section.get(key)
        if not isinstance(v, list) or len(v) != n or not all(
                isinstance(e, (int, float)) and not isinstance(e, bool) and math.isfinite(e) for e in v):
            problems.append(f"camera_in_head.{key}: expected {n} finite numbers, got {v!r}")
            return None
        return [float(e) for e in v]

    t = vector("translation_m", 3)
    if t is not None and max(abs(v) for v in t) > MAX_CAMERA_OFFSET_M:
        problems.append(f"camera_in_head.translation_m: each within +-{MAX_CAMERA_OFFSET_M:g} m of the head, got {t}")
        t = None
    R = None
    if "rpy_deg" in section and "quaternion_xyzw" in section:
        problems.append("camera_in_head: give rpy_deg or quaternion_xyzw, not both")
    elif "quaternion_xyzw" in section:
        q = vector("quaternion_xyzw", 4)
        if q is not None and math.hypot(*q) > 0 and abs(math.hypot(*q) - 1.0) > 0.01:
            problems.append(f"camera_in_head.quaternion_xyzw: not a unit quaternion (norm {math.hypot(*q):.6g}), "
                            f"got {q}")
        elif q is not None:
            try:
                R = quat_to_matrix(*q)
            except ValueError as exc:
                problems.append(f"camera_in_head.quaternion_xyzw: {exc}")
    else:
        rpy = vector("rpy_deg", 3)
        if rpy is not None and max(abs(a) for a in rpy) > 360.0:
            problems.append(f"camera_in_head.rpy_deg: each within +-360, got {rpy}")
        elif rpy is not None:
            R = rpy_to_matrix(*(a * DEG for a in rpy))
    calibrated = data.get("calibrated", False)
    if not isinstance(calibrated, bool):
        problems.append(f"calibrated: must be true or false, got {calibrated!r}")
    if problems:
        raise ValueError(f"{path}: " + "; ".join(problems))
    return CameraCalibration(make_transform(R, t), calibrated, str(path))


# -------------------------------------------------------------------------------------------------
# Lost-tracking detection
OK = "ok"
WAITING = "waiting"      # no pose yet
STALE = "stale"          # no pose for longer than stale_timeout_s
LOST = "lost"            # RTAB-Map's null pose (covariance 9999) or a zero quaternion
INVALID = "invalid"      # NaN / inf, a position outside the workspace, a quaternion that is not unit
JUMP = "jump"            # moved further than the configured limit since the last good pose


@dataclass
class GateParams:
    stale_timeout_s: float = 0.5
    lost_covariance: float = 1000.0   # any pose covariance diagonal >= this: lost (RTAB-Map: 9999)
    jump_m: float = 0.3               # position change allowed between consecutive poses ...
    jump_deg: float = 45.0            # ... and orientation change,
    max_speed_mps: float = 1.0        # plus this times the gap (gaps beyond stale_timeout_s count as
    max_rate_dps: float = 180.0       # stale_timeout_s: while stale the robot holds still)
    relock_after: int = 0             # after a jump, accept a new track after this many mutually
                                      # consistent poses; 0: never by itself (reset() re-arms)
    workspace_m: float = 100.0        # |x|, |y|, |z| of an odometry position at most this (its frame)
    quaternion_tolerance: float = 0.01  # | |q| - 1 | at most this (0 < tol <= 0.5); |q| = 0 is lost

    def problems(self):
        out = []
        for name in ("stale_timeout_s", "lost_covariance", "jump_m", "jump_deg", "max_speed_mps", "max_rate_dps",
                     "workspace_m", "quaternion_tolerance"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                out.append(f"{name}: must be a positive number, got {v!r}")
        if isinstance(self.quaternion_tolerance, (int, float)) and self.quaternion_tolerance > 0.5:
            out.append(f"quaternion_tolerance: must be at most 0.5, got {self.quaternion_tolerance!r}")
        if isinstance(self.relock_after, bool) or not isinstance(self.relock_after, int) or self.relock_after < 0:
            out.append(f"relock_after: must be a non-negative integer, got {self.relock_after!r}")
        return out


@dataclass(frozen=True)
class GateResult:
    ok: bool
    state: str
    detail: str


class TrackingGate:
    """Decides whether one odometry pose may be forwarded; tracks the stream's state.

    ``check(t_s, T, covariance_diag)`` for every message; ``state_at(now_s)`` from a timer (stale).
    """

    def __init__(self, params: Optional[GateParams] = None):
        self.params = params or GateParams()
        problems = self.params.problems()
        if problems:
            raise ValueError("invalid lost-tracking parameters: " + "; ".join(problems))
        self.reset()

    def reset(self) -> None:
        self._last_T = None
        self._last_t = None
        self._last_msg_t = None
        self._state = WAITING
        self._detail = "no pose received yet"
        self._candidate = []
        self.accepted = 0
        self.rejected = 0

    @property
    def state(self) -> str:
        return self._state

    @property
    def detail(self) -> str:
        return self._detail

    def _reject(self, state: str, detail: str) -> GateResult:
        self.rejected += 1
        self._state, self._detail = state, detail
        return GateResult(False, state, detail)

    def check(self, t_s: float, position, quaternion, covariance_diag=()) -> GateResult:
        """One odometry message: position (x, y, z), quaternion (x, y, z, w), the 6 covariance
        diagonal entries. Returns whether to forward it and, if not, why."""
        p = self.params
        self._last_msg_t = t_s
        position, quaternion = tuple(float(v) for v in position), tuple(float(v) for v in quaternion)
        covariance_diag = tuple(float(v) for v in covariance_diag)
        for field_name, values in (("position", position), ("orientation", quaternion),
                                   ("covariance", covariance_diag)):
            if not all(math.isfinite(v) for v in values):
                return self._reject(INVALID, f"non-finite {field_name} {values}")
        if any(c >= p.lost_covariance for c in covariance_diag):
            return self._reject(LOST, f"odometry lost: covariance {max(covariance_diag):g} >= "
                                      f"{p.lost_covariance:g} (null pose)")
        if any(abs(v) > p.workspace_m for v in position):
            return self._reject(INVALID, f"position {position} outside the workspace "
                                         f"(|x|, |y|, |z| <= workspace_m {p.workspace_m:g} m)")
        norm = math.hypot(*quaternion)          # no overflow for components near 1e200
        if norm == 0.0:
            return self._reject(LOST, f"odometry lost: zero quaternion {quaternion} (null pose)")
        if abs(norm - 1.0) > p.quaternion_tolerance:
            return self._reject(INVALID, f"orientation {quaternion} is not a unit quaternion "
                                         f"(norm {norm:.6g}, tolerance {p.quaternion_tolerance:g})")
        T = make_transform(quat_to_matrix(*quaternion), position)

        if self._state == JUMP and p.relock_after > 0:
            return self._relock(t_s, T)
        if self._last_T is not None:
            jump = self._jump(self._last_T, self._last_t, T, t_s)
            if jump:
                if self._state != JUMP:
                    self._candidate = [(t_s, T)]
                return self._reject(JUMP, jump)
        return self._accept(t_s, T)

    def _jump(self, T0, t0, T1, t1) -> str:
        p = self.params
        gap = min(max(t1 - t0, 0.0), p.stale_timeout_s)
        moved = float(np.linalg.norm(T1[:3, 3] - T0[:3, 3]))
        allowed = p.jump_m + p.max_speed_mps * gap
        if moved > allowed:
            return f"pose jumped {moved:.3f} m (limit {allowed:.3f} m)"
        c = (float(np.trace(T0[:3, :3].T @ T1[:3, :3])) - 1.0) / 2.0
        turned = math.degrees(math.acos(max(-1.0, min(1.0, c))))
        allowed_deg = p.jump_deg + p.max_rate_dps * gap
        if turned > allowed_deg:
            return f"orientation jumped {turned:.1f} deg (limit {allowed_deg:.1f} deg)"
        return ""

    def _relock(self, t_s, T) -> GateResult:
        t0, T0 = self._candidate[-1] if self._candidate else (None, None)
        if T0 is not None and self._jump(T0, t0, T, t_s):
            self._candidate = [(t_s, T)]
        else:
            self._candidate.append((t_s, T))
        if len(self._candidate) > self.params.relock_after:
            self._candidate = []
            self._accept(t_s, T)
            self._detail = "re-locked on a new track after a jump"
            return GateResult(True, OK, self._detail)
        return self._reject(JUMP, f"after a jump: {len(self._candidate)}/{self.params.relock_after + 1} "
                                  f"consistent poses to re-lock")

    def _accept(self, t_s, T) -> GateResult:
        self.accepted += 1
        self._last_T, self._last_t = T, t_s
        self._state, self._detail = OK, "tracking"
        return GateResult(True, OK, "tracking")

    def state_at(self, now_s: float):
        """(state, detail) at time now_s: turns OK into STALE when no message came for too long."""
        if (self._state == OK and self._last_msg_t is not None
                and now_s - self._last_msg_t > self.params.stale_timeout_s):
            self._state = STALE
            self._detail = (f"no odometry for {now_s - self._last_msg_t:.2f} s "
                            f"(timeout {self.params.stale_timeout_s:g} s)")
        elif self._state == STALE and self._last_msg_t is not None:
            self._detail = (f"no odometry for {now_s - self._last_msg_t:.2f} s "
                            f"(timeout {self.params.stale_timeout_s:g} s)")
        return self._state, self._detail


def load_gate_params(path) -> GateParams:
    """The ``lost_tracking:`` section of config/camera.yaml (absent: defaults)."""
    data = load_yaml_file(path) or {}
    section = (data.get("lost_tracking") if isinstance(data, dict) else None) or {}
    if not isinstance(section, dict):
        raise ValueError(f"{path}: lost_tracking: expected a mapping, got {type(section).__name__}")
    fields = GateParams.__dataclass_fields__
    unknown = [f"lost_tracking.{k}: unknown key (value {v!r})" for k, v in section.items() if k not in fields]
    if unknown:
        raise ValueError(f"{path}: " + "; ".join(unknown))
    params = GateParams(**section)
    problems = params.problems()
    if problems:
        raise ValueError(f"{path}: " + "; ".join("lost_tracking." + p for p in problems))
    return params


def skew(v) -> np.ndarray:
    x, y, z = (float(c) for c in v)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def base_covariance(camera_covariance, camera_in_world: np.ndarray, base_in_camera: np.ndarray) -> np.ndarray:
    """The 6x6 covariance of the base pose from the camera pose's (geometry_msgs/PoseWithCovariance
    order: x, y, z, then small rotations about the world's fixed x, y, z axes; row-major 36 or 6x6).

    The base is the camera moved by a fixed offset d = R_camera . t (base_in_camera's translation, in
    the world): a small world-frame rotation dtheta of the camera moves the base by dtheta x d, and
    turns it by the same dtheta. So Sigma_base = J Sigma_camera J^T with J = [[I, -[d]x], [0, I]]."""
    C = np.asarray(camera_covariance, dtype=float).reshape(6, 6)
    d = np.asarray(camera_in_world, dtype=float)[:3, :3] @ np.asarray(base_in_camera, dtype=float)[:3, 3]
    J = np.eye(6)
    J[:3, 3:] = -skew(d)
    return J @ C @ J.T
