"""Rendered, labelled camera frames of random obstacle scenes: training and held-out test sets.

Each scene: a random world (1-5 cylinders and boxes within 0.3-2.5 m ahead of the robot), a random
appearance (floor texture and colours, obstacle colours and marks, light: sim/scene.py), the robot
at rest at the start; one frame from the head camera with colour, depth and the segmentation
render's labels (ground truth). The same seed gives the same scenes.
"""
import math
from typing import Iterator, Optional

import numpy as np

from snake_autonomy.perception.camera_model import CameraFrame, CameraIntrinsics, CameraMount
from snake_autonomy.sim.camera import HeadCamera
from snake_autonomy.sim.plant import Plant
from snake_autonomy.sim.scene import Appearance, build_scene, random_appearance
from snake_autonomy.sim.world_file import World


def random_world(rng: np.random.Generator, min_obstacles: int = 1, max_obstacles: int = 5,
                 near_m: float = 0.3, far_m: float = 2.5, half_angle_deg: float = 30.0) -> World:
    obstacles = []
    for _ in range(int(rng.integers(min_obstacles, max_obstacles + 1))):
        r = rng.uniform(near_m, far_m)
        a = math.radians(rng.uniform(-half_angle_deg, half_angle_deg))
        x, y = r * math.cos(a), r * math.sin(a)
        if rng.random() < 0.5:
            obstacles.append({"type": "cylinder", "x": x, "y": y, "radius_m": float(rng.uniform(0.04, 0.25)),
                              "height_m": float(rng.uniform(0.06, 0.5))})
        else:
            obstacles.append({"type": "box", "x": x, "y": y,
                              "size_m": [float(s) for s in rng.uniform([0.05, 0.05, 0.06], [0.5, 0.6, 0.5])],
                              "yaw_deg": float(rng.uniform(0, 180))})
    return World.from_dict({"start": [0.0, 0.0, 0.0], "goal": [5.0, 0.0], "goal_radius_m": 0.3,
                            "obstacles": obstacles})


def render_scenes(robot, params, n: int, seed: int, intrinsics: Optional[CameraIntrinsics] = None,
                  mount: Optional[CameraMount] = None, pitch_jitter_deg: float = 3.0,
                  plain: bool = False, depth: bool = True) -> Iterator[CameraFrame]:
    """n frames of random scenes (plain: the default appearance instead of a random one; depth:
    render the depth image too)."""
    rng = np.random.default_rng(seed)
    mount = mount or CameraMount()
    for _ in range(n):
        world = random_world(rng)
        app = Appearance() if plain else random_appearance(rng)
        scene = build_scene(world, app)
        plant = Plant(robot, params, world.start_rad, scene_xml=scene.scene_xml, assets_xml=scene.assets_xml)
        rpy = np.asarray(mount.rpy_deg, float) + rng.uniform(-pitch_jitter_deg, pitch_jitter_deg, 3) * [1, 1, 0]
        cam = HeadCamera(plant.model, intrinsics, CameraMount(tuple(mount.translation_m), tuple(rpy)))
        try:
            yield cam.render(plant.data, plant.frame_transform("base_link"), depth=depth)
        finally:
            cam.close()
