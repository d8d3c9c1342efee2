"""The simulated head camera: MuJoCo offscreen renders of colour, depth and segmentation.

    cam = HeadCamera(plant.model, CameraIntrinsics.d435i_like(), mount=CameraMount(...))   # or LinkMount(T)
    frame = cam.render(plant.data, plant.frame_transform("base_link"))
    frame.rgb (H, W, 3) uint8, frame.depth_m (H, W) float32 (z along the optical axis, 0 = nothing),
    frame.labels (H, W) uint8 of LABEL_*, frame.T_world_camera (4x4, OpenCV optical frame)

depth_model: a callable applied to every depth render (sim/depth_noise.DepthNoise: the D435i's
noise and invalid pixels); None renders perfect depth.

The camera's model (intrinsics, mount, frame, labels) is perception/camera_model.py.

Only what a real camera would see is drawn: MuJoCo's debug visuals (sites, frames, labels, geoms of
groups 3-5, contact points and forces, rangefinder rays, ...) are off in the camera's mjvOption
(`HeadCamera.scene_option`, see `camera_scene_option`); base_link's site sphere 15 cm ahead of the
odometry camera had drawn about two thirds of its ORB features.

Rendering sets MuJoCo's GL frustum from the intrinsics directly, so any fx, fy, cx, cy work. MuJoCo
picks its GL backend when first imported: snake_autonomy's __init__ sets MUJOCO_GL=egl (headless)
unless it is set.
"""
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..perception.camera_model import (GROUND_GEOMS, LABEL_BACKGROUND, LABEL_GROUND, LABEL_OBSTACLE, LABEL_ROBOT,
                                       OBSTACLE_PREFIX, R_LINK_OPTICAL, CameraFrame, CameraIntrinsics, CameraMount)

NEAR_CLIP_M = 0.01                  # the head camera's near clip (rendering)
#: geom groups a camera draws (MuJoCo's default: 0-2; 3-5 hold debug-only geoms by convention)
VISIBLE_GEOM_GROUPS = (0, 1, 2)
#: MuJoCo's visualisation flags that draw debug-only things (the others draw the scene: textures,
#: tendons, skins, flexes, static bodies)
_DEBUG_VIS_FLAGS = ("mjVIS_CONVEXHULL", "mjVIS_JOINT", "mjVIS_CAMERA", "mjVIS_ACTUATOR", "mjVIS_ACTIVATION",
                    "mjVIS_LIGHT", "mjVIS_CONSTRAINT", "mjVIS_INERTIA", "mjVIS_SCLINERTIA", "mjVIS_PERTFORCE",
                    "mjVIS_PERTOBJ", "mjVIS_CONTACTPOINT", "mjVIS_ISLAND", "mjVIS_CONTACTFORCE",
                    "mjVIS_CONTACTSPLIT", "mjVIS_AUTOCONNECT", "mjVIS_COM", "mjVIS_SELECT", "mjVIS_RANGEFINDER",
                    "mjVIS_BODYBVH", "mjVIS_MESHBVH", "mjVIS_SDFITER", "mjVIS_FLEXVERT")


def camera_scene_option(mujoco):
    """The mjvOption of a simulated camera: no site group, no frames or labels, only the geoms of
    VISIBLE_GEOM_GROUPS and none of MuJoCo's debug visualisations (flags missing from an older
    MuJoCo are skipped)."""
    opt = mujoco.MjvOption()
    opt.sitegroup[:] = 0
    opt.geomgroup[:] = 0
    for g in VISIBLE_GEOM_GROUPS:
        opt.geomgroup[g] = 1
    opt.frame = int(mujoco.mjtFrame.mjFRAME_NONE)
    opt.label = int(mujoco.mjtLabel.mjLABEL_NONE)
    for name in _DEBUG_VIS_FLAGS:
        flag = getattr(mujoco.mjtVisFlag, name, None)
        if flag is not None:
            opt.flags[int(flag)] = 0
    return opt


@dataclass
class LinkMount:
    """A camera at a link frame (x forward, y left, z up) given as its 4x4 pose in base_link: the
    visual odometry's camera at the IMU's camera_link (sim/mjcf.camera_link_in_base), where a
    CameraMount is the navigation camera's mount (nav.yaml camera.mount). Either is HeadCamera's mount."""
    T_base_link: np.ndarray

    def T_base_optical(self) -> np.ndarray:
        t = np.asarray(self.T_base_link, float).copy()
        t[:3, :3] = t[:3, :3] @ R_LINK_OPTICAL
        return t


class HeadCamera:
    """Renders what a camera on the robot's head sees. One GL context per instance (reuse it)."""

    def __init__(self, model, intrinsics: Optional[CameraIntrinsics] = None,
                 mount: Optional[CameraMount] = None, max_depth_m: float = 10.0, depth_model=None):
        import mujoco  # lazy: MuJoCo is heavy and only this path needs it
        self._mujoco = mujoco
        self.model = model
        self.intrinsics = intrinsics or CameraIntrinsics.d435i_like()
        self.mount = mount or CameraMount()
        self.max_depth_m = max_depth_m
        self.depth_model = depth_model
        self.T_base_optical = self.mount.T_base_optical()
        k = self.intrinsics
        if model.vis.global_.offwidth < k.width or model.vis.global_.offheight < k.height:
            model.vis.global_.offwidth = max(model.vis.global_.offwidth, k.width)
            model.vis.global_.offheight = max(model.vis.global_.offheight, k.height)
        # MuJoCo's near clip is vis.map.znear x the model's extent: 0.064 m in the 6.4 m corridor
        # world, beyond the floor at the image's bottom (0.056 m with the head pitched): the bottom
        # rows had no depth and the region grown from the bottom was empty
        model.vis.map.znear = min(float(model.vis.map.znear), NEAR_CLIP_M / max(1e-9, float(model.stat.extent)))
        self._renderer = mujoco.Renderer(model, k.height, k.width)
        self.scene_option = camera_scene_option(mujoco)
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
        self._renderer.update_scene(data, self._free, self.scene_option)
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
            if self.depth_model is not None:
                dep = self.depth_model(dep)
        if labels:
            r.enable_segmentation_rendering()
            self._set_camera(data, T)
            seg = r.render()
            r.disable_segmentation_rendering()
            geom_ids = np.where(seg[..., 1] == int(self._mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
            lab = self._lut[geom_ids]          # -1 -> the last entry: background
        return CameraFrame(rgb, dep, lab, T, k, t_s)
