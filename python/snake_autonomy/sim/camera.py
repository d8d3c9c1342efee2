"""The simulated head camera: MuJoCo offscreen renders of colour, depth and segmentation.

    cam = HeadCamera(plant.model, CameraIntrinsics.d435i_like(), mount=CameraMount(...))
    frame = cam.render(plant.data, plant.frame_transform("base_link"))
    frame.rgb (H, W, 3) uint8, frame.depth_m (H, W) float32 (z along the optical axis, 0 = nothing),
    frame.labels (H, W) uint8 of LABEL_*, frame.T_world_camera (4x4, OpenCV optical frame)

Frames: the optical frame is OpenCV's (x right, y down, z forward); the mount is given like
config/camera.yaml's camera_link (x forward, y left, z up) in base_link, whose x axis is the
robot's forward direction (the head capsule's front cap is at its origin).

Rendering sets MuJoCo's GL frustum from the intrinsics directly, so any fx, fy, cx, cy work; the
convention is OpenCV's (pixel (u, v) centred on integer coordinates): a point (X, Y, Z) in the
optical frame lands on u = fx X / Z + cx, v = fy Y / Z + cy. MuJoCo picks its GL backend when first
imported: snake_autonomy's __init__ sets MUJOCO_GL=egl (headless) unless it is set.
"""
import math
from dataclasses import dataclass
from typing import Any, Dict, Optional, Sequence

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


NEAR_CLIP_M = 0.01                  # the head camera's near clip (rendering)


class HeadCamera:
    """Renders what a camera on the robot's head sees. One GL context per instance (reuse it)."""

    def __init__(self, model, intrinsics: Optional[CameraIntrinsics] = None,
                 mount: Optional[CameraMount] = None, max_depth_m: float = 10.0):
        import mujoco
        self._mujoco = mujoco
        self.model = model
        self.intrinsics = intrinsics or CameraIntrinsics.d435i_like()
        self.mount = mount or CameraMount()
        self.max_depth_m = max_depth_m
        self.T_base_optical = self.mount.T_base_optical()
        k = self.intrinsics
        if model.vis.global_.offwidth < k.width or model.vis.global_.offheight < k.height:
            model.vis.global_.offwidth = max(model.vis.global_.offwidth, k.width)
            model.vis.global_.offheight = max(model.vis.global_.offheight, k.height)
        # MuJoCo's near clip is vis.map.znear x the model's extent: 0.064 m in the 6.4 m corridor
        # world, beyond the floor at the image's bottom (0.056 m with the head pitched): the bottom
        # rows had no depth and the region grown from the bottom was empty (issue 13 round 4)
        model.vis.map.znear = min(float(model.vis.map.znear), NEAR_CLIP_M / max(1e-9, float(model.stat.extent)))
        self._renderer = mujoco.Renderer(model, k.height, k.width)
        self._free = mujoco.MjvCamera()
        self._free.type = mujoco.mjtCamera.mjCAMERA_FREE
        # geom id -> label (segmentation objid is a geom id for objtype mjOBJ_GEOM)
        lut = np.full(model.ngeom + 1, LABEL_BACKGROUND, np.uint8)
        for g in range(model.ngeom):
            name = model.geom(g).name
            if name in GROUND_GEOMS:
                lut[g] = LABEL_GROUND
            elif name.startswith(OBSTACLE_PREFIX):
                lut[g] = LABEL_OBSTACLE
            elif model.geom_bodyid[g] != 0:
                lut[g] = LABEL_ROBOT
            else:
                lut[g] = LABEL_OBSTACLE            # other static scenery is not ground
        self._lut = lut

    def close(self) -> None:
        self._renderer.close()

    def T_world_camera(self, T_world_base: np.ndarray) -> np.ndarray:
        return np.asarray(T_world_base, float) @ self.T_base_optical

    def _set_camera(self, data, T_world_cam: np.ndarray) -> None:
        self._renderer.update_scene(data, self._free)
        k = self.intrinsics
        for i in range(2):
            g = self._renderer.scene.camera[i]
            g.pos[:] = T_world_cam[:3, 3]
            g.forward[:] = T_world_cam[:3, 2]
            g.up[:] = -T_world_cam[:3, 1]
            n = g.frustum_near
            # OpenCV pixel centres are integers: the image's left edge is at u = -0.5.
            left, right = -(k.cx + 0.5) / k.fx * n, (k.width - k.cx - 0.5) / k.fx * n
            g.frustum_top = (k.cy + 0.5) / k.fy * n
            g.frustum_bottom = -(k.height - k.cy - 0.5) / k.fy * n
            g.frustum_center = 0.5 * (left + right)
            g.frustum_width = 0.5 * (right - left)

    def render(self, data, T_world_base: np.ndarray, t_s: float = 0.0,
               colour: bool = True, depth: bool = True, labels: bool = True) -> CameraFrame:
        """Render the frames asked for (each costs one render pass); the others are empty."""
        k = self.intrinsics
        T = self.T_world_camera(T_world_base)
        r = self._renderer
        rgb = np.zeros((k.height, k.width, 3), np.uint8)
        dep = np.zeros((k.height, k.width), np.float32)
        lab = np.full((k.height, k.width), LABEL_BACKGROUND, np.uint8)
        if colour:
            self._set_camera(data, T)
            rgb = r.render().copy()
        if depth:
            r.enable_depth_rendering()
            self._set_camera(data, T)
            dep = r.render().astype(np.float32)
            r.disable_depth_rendering()
            dep[~np.isfinite(dep) | (dep > self.max_depth_m)] = 0.0
        if labels:
            r.enable_segmentation_rendering()
            self._set_camera(data, T)
            seg = r.render()
            r.disable_segmentation_rendering()
            geom_ids = np.where(seg[..., 1] == int(self._mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
            lab = self._lut[geom_ids]          # -1 -> the last entry: background
        return CameraFrame(rgb, dep, lab, T, k, t_s)
