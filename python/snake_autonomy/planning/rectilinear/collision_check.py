"""Perception-space collision checks (Chang et al. III): a path's poses, the head's footprint at
each projected into the current traversability image; free while every projected pixel is ground.

The ground frame: the robot's current pose on the floor (x forward, y left, z up, origin under
base_link). T_ground_camera: the camera's optical frame in it (OpenCV: x right, y down, z forward).
The footprint at a pose is the segment across the head, width head_width_m (51 mm on Chang's robot),
sampled at `footprint_points` points (a line, as in the paper: the image is a homography of the
floor, so only the footprint on the floor is hallucinated).

Points nearer (ahead of the camera, along its heading on the floor) than near_field_m are hidden
from the view and count as free: the robot is there or saw that floor on its way. near_field_m is
the larger of where the image's bottom row meets the floor and where the view becomes as wide as
the head (a head wider than the view at its own front: COBRA's 90 mm at 5 cm up). Points anywhere
else outside the image (beside or beyond the field of view) are not known to be free.
"""
import math

import cv2
import numpy as np


class PerceptionCollisionChecker:
    def __init__(self, intrinsics, T_ground_camera: np.ndarray, head_width_m: float,
                 footprint_points: int = 5):
        self.k = intrinsics
        self.K = intrinsics.K()
        self.dist = np.zeros(5)
        T_cam_ground = np.linalg.inv(np.asarray(T_ground_camera, float))
        self.rvec, _ = cv2.Rodrigues(T_cam_ground[:3, :3])
        self.tvec = T_cam_ground[:3, 3].copy()
        self._R, self._t = T_cam_ground[:3, :3], T_cam_ground[:3, 3]
        # the camera's position and heading on the floor; the near field hidden under the view
        T = np.asarray(T_ground_camera, float)
        self._cam_xy = T[:2, 3]
        fwd = T[:2, 2] / max(1e-9, np.linalg.norm(T[:2, 2]))
        self._cam_fwd = fwd
        ray = T[:3, :3] @ np.array([0.0, (intrinsics.height - 1 - intrinsics.cy) / intrinsics.fy, 1.0])
        bottom = float(-T[2, 3] / ray[2] * (ray[:2] @ fwd)) if ray[2] < 0 else 0.0
        half_fov = math.atan2(min(intrinsics.cx, intrinsics.width - intrinsics.cx), intrinsics.fx)
        self.near_field_m = max(bottom, 0.5 * head_width_m / math.tan(half_fov))
        self.offsets = np.linspace(-0.5 * head_width_m, 0.5 * head_width_m, footprint_points)

    def footprint_points(self, poses: np.ndarray) -> np.ndarray:
        """(N, 3) poses -> (N, P, 3) ground points of the head's footprint at each."""
        poses = np.asarray(poses, float)
        nx, ny = -np.sin(poses[:, 2]), np.cos(poses[:, 2])           # left normal
        x = poses[:, 0:1] + nx[:, None] * self.offsets[None, :]
        y = poses[:, 1:2] + ny[:, None] * self.offsets[None, :]
        return np.dstack([x, y, np.zeros_like(x)])

    def pose_free(self, poses: np.ndarray, ground: np.ndarray) -> np.ndarray:
        """(N,) bool: every footprint point of the pose is ground (or hidden below the image)."""
        pts = self.footprint_points(poses)
        n, p = pts.shape[:2]
        flat = pts.reshape(-1, 3)
        z = flat @ self._R[2] + self._t[2]                            # depth in the camera
        uv, _ = cv2.projectPoints(flat, self.rvec, self.tvec, self.K, self.dist)
        uv = uv.reshape(-1, 2)
        u = np.round(uv[:, 0]).astype(np.int64)
        v = np.round(uv[:, 1]).astype(np.int64)
        h, w = ground.shape
        inside = (z > 0) & (u >= 0) & (u < w) & (v >= 0) & (v < h)
        ok = (flat[:, :2] - self._cam_xy) @ self._cam_fwd < self.near_field_m
        inside &= ~ok
        ok[inside] = ground[v[inside], u[inside]]
        return ok.reshape(n, p).all(axis=1)

    def free_length(self, poses: np.ndarray, ground: np.ndarray, s_m: np.ndarray) -> float:
        """Arc length s_m of the last pose of the path's collision-free prefix (0 if pose 0 is not
        free)."""
        return prefix_length(self.pose_free(poses, ground), s_m)


def prefix_length(free: np.ndarray, s_m: np.ndarray) -> float:
    """s of the last pose before the first non-free one (s of the last pose if all are free)."""
    if free.all():
        return float(s_m[-1])
    return float(s_m[max(0, int(np.argmin(free)) - 1)])
