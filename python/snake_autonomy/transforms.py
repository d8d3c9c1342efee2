"""Rigid-body helpers shared by the estimation, simulation and node code (no ROS).

Rotations go through scipy's `Rotation` (quaternion <-> matrix, rotation vectors, Euler angles);
this module only fixes the package's conventions on top of it:
- quaternions are (x, y, z, w), as in geometry_msgs and scipy; MuJoCo's (w, x, y, z) is converted
  where MuJoCo is called;
- `T_a_in_b` (4x4) is the pose of frame a in frame b: p_b = T_a_in_b @ p_a (the thesis's T_a^b).
"""
import math

import numpy as np
from scipy.spatial.transform import Rotation


def rot_x(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_to_matrix(roll_rad: float, pitch_rad: float, yaw_rad: float) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) (URDF / tf convention, fixed axes x-y-z)."""
    return Rotation.from_euler("xyz", [roll_rad, pitch_rad, yaw_rad]).as_matrix()


def rotvec_to_matrix(rotvec) -> np.ndarray:
    """Rotation matrix of a rotation vector (axis * angle, rad)."""
    return Rotation.from_rotvec(np.asarray(rotvec, dtype=float)).as_matrix()


def make_transform(rotation=None, translation=None) -> np.ndarray:
    """4x4 homogeneous transform from a 3x3 rotation and a 3-vector (either may be omitted)."""
    T = np.eye(4)
    if rotation is not None:
        T[:3, :3] = rotation
    if translation is not None:
        T[:3, 3] = translation
    return T


def translation(x: float, y: float, z: float) -> np.ndarray:
    return make_transform(translation=[x, y, z])


def invert(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid transform: [R^T, -R^T p]."""
    R = T[:3, :3]
    out = np.eye(4)
    out[:3, :3] = R.T
    out[:3, 3] = -R.T @ T[:3, 3]
    return out


def quat_to_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Rotation matrix of a quaternion (normalised first; ValueError on a zero or non-finite one)."""
    q = np.array([x, y, z, w], dtype=float)
    n = float(np.linalg.norm(q))
    if not math.isfinite(n) or n < 1e-9:
        raise ValueError(f"quaternion: must be finite and non-zero, got {tuple(q)}")
    return Rotation.from_quat(q / n).as_matrix()


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """(x, y, z, w) of a rotation matrix, with w >= 0.

    R must already be a rotation (from kinematics, MuJoCo or a product of rotations): scipy's
    re-orthonormalisation is skipped (assume_valid), which costs 90 µs a call against 15 µs, and
    this runs for every simulated sensor sample."""
    q = Rotation.from_matrix(np.asarray(R, dtype=float), assume_valid=True).as_quat()
    return -q if q[3] < 0 else q


def pose_to_matrix(position, quaternion) -> np.ndarray:
    """4x4 from (x, y, z) and (qx, qy, qz, qw)."""
    return make_transform(quat_to_matrix(*quaternion), position)


def matrix_to_pose(T: np.ndarray):
    """((x, y, z), (qx, qy, qz, qw)) of a 4x4, as tuples of floats (ready for a message)."""
    return tuple(float(v) for v in T[:3, 3]), tuple(float(v) for v in matrix_to_quat(T[:3, :3]))


def yaw_of_quat(x: float, y: float, z: float, w: float) -> float:
    """Yaw (rotation about world z, REP 103) of a quaternion: the heading of its x axis."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def rotation_angle(R: np.ndarray) -> float:
    """Angle (rad, [0, pi]) of a rotation matrix."""
    c = (float(np.trace(R)) - 1.0) / 2.0
    return math.acos(max(-1.0, min(1.0, c)))
