"""The odometry room is lit like a lab under diffuse ceiling lights: the robot casts no shadow into
the odometry camera's colour frames. Seen from above at 45 deg, the floor around the robot lifted
10 cm looks the same as with the robot gone; the same room with one shadow-casting light added
fails that comparison (so the comparison can see a shadow)."""
import math

import mujoco
import numpy as np
from scipy.ndimage import binary_dilation

from snake_autonomy.perception.camera_model import LABEL_GROUND
from snake_autonomy.sim.camera import HeadCamera, LinkMount
from snake_autonomy.sim.mjcf import OVERHEAD_LIGHT
from snake_autonomy.sim.scene import vo_room
from snake_autonomy.sim.vo_feedback import ODOMETRY_CAMERA
from snake_autonomy.sim.world import SimWorld, WorldSpec
from snake_autonomy.transforms import make_transform, rot_y, rot_z

LIFT_M = 0.10
#: the camera 0.7 m beside the body and 0.7 m up, looking at it 45 deg down
T_WORLD_VIEW = make_transform(rot_z(math.pi / 2) @ rot_y(math.pi / 4), (-0.4, -0.7, 0.7))


def _floor_pixels_changed(scene_xml: str, assets_xml: str) -> int:
    """Floor pixels (the floor in both renders, beyond 2 px of the robot's antialiased outline) more
    than 16 grey levels apart between the robot lifted LIFT_M and the robot 20 m away, in the odometry
    camera's colour render from T_WORLD_VIEW."""
    world = SimWorld(WorldSpec(feedback="mocap", sensors=("mocap",), mission="", scene_xml=scene_xml,
                               assets_xml=assets_xml))
    model, data = world.plant.model, world.plant.data
    cam = HeadCamera(model, ODOMETRY_CAMERA.intrinsics(), LinkMount(np.eye(4)))
    frames = []
    try:
        for dx, dz in ((0.0, LIFT_M), (20.0, 0.0)):
            data.qpos[0] += dx
            data.qpos[2] += dz
            mujoco.mj_kinematics(model, data)
            frames.append(cam.render(data, T_WORLD_VIEW, depth=False, labels=True))
            data.qpos[0] -= dx
            data.qpos[2] -= dz
    finally:
        cam.close()
    with_robot, without = frames
    robot = with_robot.labels != LABEL_GROUND
    assert robot.sum() > 500                                        # the robot is in view
    floor = ~binary_dilation(robot, iterations=2) & (without.labels == LABEL_GROUND)
    diff = np.abs(with_robot.rgb.astype(int) - without.rgb.astype(int)).max(axis=2)
    return int((diff[floor] > 16).sum())


def test_the_robot_casts_no_shadow_in_the_odometry_room():
    room = vo_room((0.0, 0.0))
    assert _floor_pixels_changed(room.scene_xml, room.assets_xml) == 0


def test_a_shadow_casting_light_in_the_room_shows_the_robots_shadow():
    room = vo_room((0.0, 0.0))
    changed = _floor_pixels_changed(f"    {OVERHEAD_LIGHT}\n" + room.scene_xml, room.assets_xml)
    assert changed > 300, changed
