"""The odometry room sim_node builds with feedback:=vo fits the default star mission: flown in the
odometry frame (camera_link's start, levelled), each of its waypoints keeps COBRA's whole body
0.8 m from every wall, and the room is textured."""
import math

import numpy as np
import pytest

from snake_autonomy.sim.scene import vo_room, vo_room_around_camera
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


def test_walls_and_floor_are_textured():
    room = vo_room((1.0, -2.0))
    assert room.scene_xml.count('material="wall_mat_') == 4
    assert 'mark="random"' in room.assets_xml and 'material="floor_mat"' in room.scene_xml


def test_a_room_without_size_is_refused():
    with pytest.raises(ValueError, match="half_m.*-1"):
        vo_room(half_m=-1.0)
