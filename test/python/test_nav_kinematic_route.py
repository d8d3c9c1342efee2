"""The route in the robot's own motions (planning/rectilinear/kinematic_route.py): a path the robot
can drive (its turning circle), clear of the map, repeatable, and the cost to go the critic reads."""
import math

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear.grid_route import GridRoute
from snake_autonomy.planning.rectilinear.kinematic_route import KinematicRoute
from snake_autonomy.planning.rectilinear.local_map import LocalMap, LocalMapParams

C_MAX = 3.6                     # the 12-link robot's tightest arc (radius 0.28 m)
NEED = 0.066                    # its head's footprint, half a side


def _map(points=()):
    m = LocalMap(LocalMapParams(size_m=4.0))
    m._place((0.0, 0.0))
    if len(points):
        i, j, _ = m.cells(np.asarray(points, float))
        m.log_odds[i, j] = 3.0
    return m


def _plan(m, start, goal, radius=0.15):
    grid = GridRoute(0.08, 0.12, 0.045)
    grid.update(m, start[:2], goal)
    route = KinematicRoute(C_MAX, NEED)
    return route, grid, route.plan(m, grid, start, goal, radius)


def _curvature(path):
    ds = np.hypot(*np.diff(path[:, :2], axis=0).T)
    dth = np.abs(np.angle(np.exp(1j * np.diff(path[:, 2]))))
    return dth / ds


def test_a_goal_behind_the_robot_is_reached_on_its_turning_circle_not_on_the_spot():
    m = _map()
    route, grid, path = _plan(m, (0.0, 0.0, 0.0), (-0.6, 0.0))
    assert path is not None
    assert np.hypot(*(path[-1, :2] - (-0.6, 0.0))) <= 0.15
    assert np.max(_curvature(path)) <= C_MAX * 1.01               # no tighter than the tightest arc
    assert path[1, 0] > 0.0                                        # it starts forward, the way it faces
    length = np.sum(np.hypot(*np.diff(path[:, :2], axis=0).T))
    assert length > 0.6 + 0.5 * math.pi / C_MAX                    # a half turn at least, not the 0.45 m
    # straight back that the grid route's cost to go says
    assert grid.cost_to_go(np.array([[0.0, 0.0]]))[0] < 0.7


def test_the_path_keeps_the_heads_footprint_off_a_wall_and_goes_through_its_gap():
    wall = [(1.0, y) for y in np.arange(-2.0, 2.0, 0.02) if abs(y - 0.8) > 0.25]
    m = _map(wall)
    _, _, path = _plan(m, (0.0, 0.0, 0.0), (2.0, 0.0))
    assert path is not None
    assert np.min(m.distance(path[:, :2])) >= NEED - 1e-9
    crossing = path[np.argmin(np.abs(path[:, 0] - 1.0))]
    assert abs(crossing[1] - 0.8) < 0.2


def test_the_same_map_gives_the_same_path():
    wall = [(1.0, y) for y in np.arange(-2.0, 2.0, 0.02) if abs(y + 0.5) > 0.25]
    a = _plan(_map(wall), (0.0, 0.0, 0.3), (1.8, 0.4))[2]
    b = _plan(_map(wall), (0.0, 0.0, 0.3), (1.8, 0.4))[2]
    assert a is not None and np.array_equal(a, b)


def test_no_path_when_the_goal_is_walled_off_within_the_search():
    ring = [(0.8 * math.cos(t), 0.8 * math.sin(t)) for t in np.linspace(0, 2 * math.pi, 400)]
    m = _map(ring)
    grid = GridRoute(0.08, 0.12, 0.045)
    grid.update(m, (0.0, 0.0), (1.5, 0.0))
    route = KinematicRoute(C_MAX, NEED, max_expansions=3000)
    assert route.plan(m, grid, (0.0, 0.0, 0.0), (1.5, 0.0), 0.15) is None
    assert route.path is None
    assert route.expansions <= 3000
    assert route.cost_to_go(np.array([[0.0, 0.0, 0.0]]), np.array([7.0]))[0] == 7.0   # the grid's


def test_cost_to_go_counts_the_turn_to_the_paths_heading():
    route, grid, path = _plan(_map(), (0.0, 0.0, 0.0), (1.5, 0.0))
    assert path is not None
    i = len(path) // 3
    on = path[i]
    ahead = route.cost_to_go(on[None], np.zeros(1))[0]
    against = route.cost_to_go(np.array([[on[0], on[1], on[2] + math.pi]]), np.zeros(1))[0]
    assert ahead == pytest.approx(route._rem[i], abs=1e-6)
    assert against > ahead + 0.9 * math.pi / C_MAX                 # half a turn at the turning radius
    assert route.cost_to_go(on[None], np.array([99.0]))[0] == ahead      # the path's, not the grid's


def test_refuses_a_turning_circle_of_no_size():
    with pytest.raises(ValueError, match="max_curvature_per_m"):
        KinematicRoute(0.0, NEED)


def _two_ways(shorter=0.0, side=1.0):
    """A block between the robot and the goal, 0.6 m long across the way: round it left or right;
    its end on `side` `shorter` m nearer the middle."""
    return _map([(0.8, side * y) for y in np.arange(-0.3, 0.3 - shorter, 0.02)])


def test_the_robot_keeps_its_way_round_unless_the_other_is_much_cheaper():
    m = _two_ways(0.0)
    grid = GridRoute(0.08, 0.12, 0.045)
    route = KinematicRoute(C_MAX, NEED)
    grid.update(m, (0.0, 0.0), (1.8, 0.0))
    first = route.plan(m, grid, (0.0, 0.0, 0.0), (1.8, 0.0), 0.15)
    side = np.sign(first[np.argmin(np.abs(first[:, 0] - 0.8)), 1])
    # the block's other end a little shorter: the other way is now a bit cheaper
    m2 = _two_ways(0.06, -side)
    grid.update(m2, (0.0, 0.0), (1.8, 0.0))
    again = route.plan(m2, grid, (0.0, 0.0, 0.0), (1.8, 0.0), 0.15)
    assert np.sign(again[np.argmin(np.abs(again[:, 0] - 0.8)), 1]) == side
    fresh = KinematicRoute(C_MAX, NEED).plan(m2, grid, (0.0, 0.0, 0.0), (1.8, 0.0), 0.15)
    assert np.sign(fresh[np.argmin(np.abs(fresh[:, 0] - 0.8)), 1]) == -side     # planned anew: the other


def test_a_kept_path_the_map_now_blocks_is_replanned():
    m = _two_ways(0.0)
    grid = GridRoute(0.08, 0.12, 0.045)
    route = KinematicRoute(C_MAX, NEED)
    grid.update(m, (0.0, 0.0), (1.8, 0.0))
    first = route.plan(m, grid, (0.0, 0.0, 0.0), (1.8, 0.0), 0.15)
    side = np.sign(first[np.argmin(np.abs(first[:, 0] - 0.8)), 1])
    wall = [(0.8, y) for y in np.arange(-0.3, 0.3, 0.02)] + [(0.8, side * y) for y in np.arange(0.3, 2.0, 0.02)]
    m2 = _map(wall)                                                # the side taken walled off
    grid.update(m2, first[3, :2], (1.8, 0.0))
    again = route.plan(m2, grid, first[3], (1.8, 0.0), 0.15)
    assert again is not None
    assert np.sign(again[np.argmin(np.abs(again[:, 0] - 0.8)), 1]) == -side
    assert np.min(m2.distance(again[:, :2])) >= NEED - 1e-9
