"""The head camera's model: pinhole intrinsics, its mount on the head, and one frame's images.

Frames: the optical frame is OpenCV's (x right, y down, z forward); the mount is given like
config/camera.yaml's camera_link (x forward, y left, z up) in base_link, whose x axis is the
robot's forward direction (the head capsule's front cap is at its origin). A point (X, Y, Z) in the
optical frame lands on u = fx X / Z + cx, v = fy Y / Z + cy (OpenCV's convention: pixel (u, v)
centred on integer coordinates).

Used alike by perception, the navigation planner's configuration, the simulator's renderer
(sim/camera.py) and the ROS image conversions (nodes/image_msgs.py).
"""
import math
from dataclasses import dataclass
from typing import Any, Dict, Sequence

import numpy as np

LABEL_GROUND, LABEL_OBSTACLE, LABEL_ROBOT, LABEL_BACKGROUND = 0, 1, 2, 3
#: geom names that are ground (the physical floor and the textured visual floor of sim/scene.py)
GROUND_GEOMS = ("floor", "floor_visual")
OBSTACLE_PREFIX = "obstacle_"


@dataclass(frozen=True)
class CameraIntrinsics:
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def d435i_like(cls) -> "CameraIntrinsics":
        """The colour stream of a RealSense D435i at 640x480 (typical factory values)."""
        return cls(640, 480, 615.0, 615.0, 320.0, 240.0)

    @classmethod
    def from_dict(cls, d: Dict[str, Any], where: str = "camera.intrinsics") -> "CameraIntrinsics":
        problems = []
        vals = {}
        for key in ("width", "height", "fx", "fy", "cx", "cy"):
            v = d.get(key) if isinstance(d, dict) else None
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v) or v <= 0:
                problems.append(f"{where}.{key}: must be a number > 0, got {v!r}")
            vals[key] = v
        if problems:
            raise ValueError("; ".join(problems))
        return cls(int(vals["width"]), int(vals["height"]), float(vals["fx"]), float(vals["fy"]),
                   float(vals["cx"]), float(vals["cy"]))

    def K(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def camera_info(self, frame_id: str = "camera_color_optical_frame") -> Dict[str, Any]:
        """The fields of a sensor_msgs/CameraInfo (plumb_bob, no distortion)."""
        k = self.K()
        p = np.hstack([k, np.zeros((3, 1))])
        return {"header": {"frame_id": frame_id}, "width": self.width, "height": self.height,
                "distortion_model": "plumb_bob", "D": [0.0] * 5, "K": k.ravel().tolist(),
                "R": np.eye(3).ravel().tolist(), "P": p.ravel().tolist()}

    def project(self, points_cam: np.ndarray) -> np.ndarray:
        """(N, 3) optical-frame points -> (N, 2) pixel coordinates (no check of Z > 0)."""
        p = np.asarray(points_cam, float)
        return np.column_stack([self.fx * p[:, 0] / p[:, 2] + self.cx,
                                self.fy * p[:, 1] / p[:, 2] + self.cy])

    def back_project(self, depth_m: np.ndarray) -> np.ndarray:
        """(H, W) depth -> (H, W, 3) optical-frame points."""
        v, u = np.mgrid[0:self.height, 0:self.width]
        z = np.asarray(depth_m, float)
        return np.dstack([(u - self.cx) * z / self.fx, (v - self.cy) * z / self.fy, z])


def _rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


#: camera_link (x forward, y left, z up) -> OpenCV optical frame (x right, y down, z forward)
R_LINK_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


@dataclass(frozen=True)
class CameraMount:
    """camera_link in base_link: translation (m) and roll, pitch, yaw (deg; + pitch looks down)."""
    translation_m: Sequence[float] = (0.05, 0.0, 0.0)
    rpy_deg: Sequence[float] = (0.0, 15.0, 0.0)

    def T_base_optical(self) -> np.ndarray:
        t = np.eye(4)
        t[:3, :3] = _rpy_matrix(*np.radians(self.rpy_deg)) @ R_LINK_OPTICAL
        t[:3, 3] = self.translation_m
        return t


@dataclass
class CameraFrame:
    rgb: np.ndarray                 # (H, W, 3) uint8
    depth_m: np.ndarray             # (H, W) float32, z along the optical axis; 0 where nothing
    labels: np.ndarray              # (H, W) uint8 LABEL_*
    T_world_camera: np.ndarray      # 4x4, optical frame in the world
    intrinsics: CameraIntrinsics
    t_s: float = 0.0

    def ground_truth_ground(self) -> np.ndarray:
        """Boolean image: the pixel shows the floor (the segmentation render's ground)."""
        return self.labels == LABEL_GROUND
