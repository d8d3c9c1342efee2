"""The odometry room sim_node builds with feedback:=vo fits the default star mission: flown in the
odometry frame (camera_link's start, levelled), each of its waypoints keeps COBRA's whole body
0.8 m from every wall, and the room is textured."""
import math

import numpy as np
import pytest

from snake_autonomy.sim.scene import VO_ROOM_CEILING_M, vo_room, vo_room_around_camera
from snake_autonomy.sim.world import SimWorld, WorldSpec

WALL_MARGIN_M = 0.8


def _inner_walls(model):
    """(axis, inner face coordinate, sign towards the room) of each obstacle_<k> wall box."""
    walls = []
    for g in range(model.ngeom):
        if not model.geom(g).name.startswith("obstacle_"):
            continue
        pos, size = model.geom_pos[g], model.geom_size[g]
        axis = 0 if size[0] < size[1] else 1                   # the wall's thin axis
        walls.append((axis, pos[axis], size[axis]))
    return walls


@pytest.fixture(scope="module")
def star_in_room():
    spec = WorldSpec(feedback="mocap", sensors=("mocap", "imu"), mission="star")
    room = vo_room_around_camera(spec)
    world = SimWorld(WorldSpec(feedback="mocap", sensors=("mocap", "imu"), mission="star",
                               scene_xml=room.scene_xml, assets_xml=room.assets_xml))
    return world


def test_every_star_waypoint_keeps_the_body_away_from_the_walls(star_in_room):
    world = star_in_room
    plant = world.plant
    T0 = plant.frame_transform("head_link") @ world.camera_in_head     # the odometry frame's origin
    yaw = math.atan2(T0[1, 0], T0[0, 0])
    c, s = math.cos(yaw), math.sin(yaw)
    com = plant.center_of_mass()[:2]
    # the body's reach from its centre of mass (the straight start shape) plus the links' radius
    body_xy = plant.frame_positions()[:, :2]
    reach = float(np.max(np.linalg.norm(body_xy - com, axis=1))) + 0.05
    assert reach > 0.5                                                 # COBRA: about 0.8 m
    walls = _inner_walls(plant.model)
    assert len(walls) == 4
    waypoints = world.mission.waypoints
    assert len(waypoints) == 5
    for i, (x, y, _) in enumerate(waypoints):
        p = T0[:2, 3] + np.array([c * x - s * y, s * x + c * y])
        for axis, centre, half_thick in walls:
            inside = p[axis] < centre - half_thick if centre > p[axis] else p[axis] > centre + half_thick
            assert inside, f"waypoint {i} at {p} outside the wall at {centre}"
            clearance = abs(p[axis] - centre) - half_thick - reach
            assert clearance >= WALL_MARGIN_M, f"waypoint {i}: body {clearance:.2f} m from a wall"


def test_the_room_is_centred_where_the_camera_starts(star_in_room):
    world = star_in_room
    T0 = world.plant.frame_transform("head_link") @ world.camera_in_head
    walls = _inner_walls(world.plant.model)
    for axis in (0, 1):
        lo, hi = sorted(centre for a, centre, _ in walls if a == axis)
        assert 0.5 * (lo + hi) == pytest.approx(T0[axis, 3], abs=0.01)
    # with the ceiling (VO_ROOM_CEILING_M) the walls reach up to it
    ceiling = world.plant.model.geom("ceiling_visual")
    assert ceiling.pos[2] - ceiling.size[2] == pytest.approx(VO_ROOM_CEILING_M, abs=1e-6)


def test_walls_and_floor_are_textured():
    room = vo_room((1.0, -2.0))
    assert room.scene_xml.count('material="wall_mat_') == 4
    assert 'mark="random"' in room.assets_xml and 'material="floor_mat"' in room.scene_xml


def test_a_room_without_size_is_refused():
    with pytest.raises(ValueError, match="half_m.*-1"):
        vo_room(half_m=-1.0)


def _camera_view(room, xy, yaw_rad=0.0):
    """The depth a level 320x240 camera 4.5 cm above the floor at xy, looking along yaw_rad, renders in
    the room (perfect depth)."""
    mujoco = pytest.importorskip("mujoco")
    from snake_autonomy.perception.camera_model import CameraIntrinsics
    from snake_autonomy.sim.camera import HeadCamera, LinkMount
    model = mujoco.MjModel.from_xml_string(f"<mujoco><asset>{room.assets_xml}</asset>"
                                           f"<worldbody>{room.scene_xml}</worldbody></mujoco>")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    cam = HeadCamera(model, CameraIntrinsics(320, 240, 307.5, 307.5, 159.5, 119.5), mount=LinkMount(np.eye(4)))
    T = np.eye(4)
    T[:3, :3] = [[math.cos(yaw_rad), -math.sin(yaw_rad), 0], [math.sin(yaw_rad), math.cos(yaw_rad), 0], [0, 0, 1]]
    T[:3, 3] = (xy[0], xy[1], 0.045)
    try:
        return cam.render(data, T, colour=False, labels=False).depth_m
    finally:
        cam.close()


def test_the_ceiling_gives_depth_within_range_where_the_far_wall_has_none():
    """Across the room the wall is 4.3 m away, beyond the D435i's 4 m: the upper half of the image has
    nothing within range without the ceiling; the ceiling 0.8 m up fills its upper part."""
    far_from_wall = (-1.06, 1.01)                       # looking along +x: the wall 4.26 m ahead
    open_room = _camera_view(vo_room(), far_from_wall)
    upper = slice(0, 100)
    assert open_room[upper].min() > 4.0
    with_ceiling = _camera_view(vo_room(ceiling_m=0.8), far_from_wall)
    within = (with_ceiling[upper] > 0) & (with_ceiling[upper] <= 4.0)
    assert within.mean() > 0.3, within.mean()


def test_the_ceiling_is_visual_only_and_the_walls_reach_it():
    room = vo_room(ceiling_m=0.8)
    assert 'name="ceiling_visual"' in room.scene_xml
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_string(f"<mujoco><asset>{room.assets_xml}</asset>"
                                           f"<worldbody>{room.scene_xml}</worldbody></mujoco>")
    g = model.geom("ceiling_visual")
    assert g.contype[0] == 0 and g.conaffinity[0] == 0
    assert g.pos[2] - g.size[2] == pytest.approx(0.8, abs=1e-6)
    wall = model.geom("obstacle_0")
    assert wall.pos[2] + wall.size[2] == pytest.approx(0.8, abs=1e-6)
    with pytest.raises(ValueError, match="ceiling_m.*0"):
        vo_room(ceiling_m=0.0)
