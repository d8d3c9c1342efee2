"""The obstacle map (obstacle_map.py): the faces the views show, each with a prior on the obstacle's
unseen extent behind it, answer for the points no image shows. A later view's floor clears what an
earlier one took for an obstacle; a prior is not laid on floor its own view shows
(map.priors_off_own_floor)."""
import dataclasses

import numpy as np
import pytest
from shapely.geometry import Point

from nav_scenes import CFG, K, T_GC, drawn_mask
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.obstacle_map import MapParams, ObstacleMap, view_on_floor
from snake_autonomy.runs.nav_experiment import random_corridor


CYL = (0.6, 0.0, 0.06)


def test_faces_lie_on_the_near_side_and_the_prior_covers_the_unseen_far_side():
    pts, dirs, floor = view_on_floor(drawn_mask(discs=[CYL]), K.K(), T_GC, max_range_m=1.5, column_step_px=2)
    assert len(pts) > 10
    r = np.hypot(pts[:, 0] - CYL[0], pts[:, 1] - CYL[1])
    assert np.all(np.abs(r - CYL[2]) < 0.02), r            # on the cylinder's outline
    assert np.all(pts[:, 0] < CYL[0] + 0.01)                # the side facing the camera
    assert np.allclose(np.hypot(*dirs.T), 1.0)
    m = ObstacleMap()
    m.add_view(pts, dirs, floor, 0.1)
    far_side = [[CYL[0] + 0.05, 0.0], [CYL[0] + 0.03, 0.045]]   # no view shows these
    assert m.blocked(np.array(far_side)).all()
    assert not m.blocked(np.array([[0.3, 0.0], [0.6, 0.3], [0.6, -0.3], [0.9, 0.0]])).any()
    # open floor: no faces (the ground reaches the horizon or max_range_m), the floor seen up to 1.5 m
    pts, _, floor = view_on_floor(drawn_mask(), K.K(), T_GC, 1.5)
    assert len(pts) == 0
    assert floor.contains(Point(1.4, 0.0)) and not floor.contains(Point(1.6, 0.0))
    assert not floor.contains(Point(0.03, 0.0))                   # under the camera: not in view


def test_a_later_view_that_shows_floor_clears_what_an_earlier_one_took_for_an_obstacle():
    m = ObstacleMap()
    # a face 0.5 m ahead (e.g. the far floor the depth test marked unsure), then the floor seen there
    m.add_view(np.array([[0.5, 0.0]]), np.array([[1.0, 0.0]]), None, 0.1)
    assert m.blocked(np.array([[0.55, 0.0]]))[0]
    _, _, floor = view_on_floor(drawn_mask(), K.K(), T_GC, 1.5)
    m.add_view(np.zeros((0, 2)), np.zeros((0, 2)), floor, 0.1)
    assert not m.blocked(np.array([[0.55, 0.0]]))[0]
    # a cylinder's own face survives the view that shows it (its floor ends at the face)
    pts, dirs, floor = view_on_floor(drawn_mask(discs=[CYL]), K.K(), T_GC, 1.5, 2, edge_px=6)
    m.add_view(pts, dirs, floor, 0.1)
    assert m.blocked(np.array([[CYL[0], 0.0], [CYL[0] + 0.05, 0.0]])).all()


def test_the_map_knows_the_worlds_obstacles():
    world = random_corridor(6)
    truth = ObstacleMap.from_world(world.obstacles)
    for ob in world.obstacles:
        assert truth.blocked(np.array([[ob.x_m, ob.y_m]]))[0]
        assert not truth.blocked(np.array([[ob.x_m + ob.footprint_radius_m() + 0.01, ob.y_m]]))[0]


def test_a_rotated_box_is_mapped_by_its_corners():
    from snake_autonomy.sim.world_file import Obstacle
    box = Obstacle("box", 1.0, 0.5, size_m=(0.4, 0.1, 0.3), yaw_deg=90.0)
    assert np.allclose(sorted(box.corners()), sorted([(1.05, 0.7), (0.95, 0.7), (0.95, 0.3), (1.05, 0.3)]))
    m = ObstacleMap.from_world([box])
    assert m.blocked(np.array([[1.0, 0.68], [1.0, 0.32]])).all()        # along its long side, now y
    assert not m.blocked(np.array([[1.15, 0.5], [0.85, 0.5]])).any()


def test_the_maps_distance():
    m = ObstacleMap(Point(1.0, 0.0).buffer(0.1, 64))
    d = m.distance(np.array([[1.0, 0.0], [1.3, 0.0], [1.0, -0.5]]))
    assert d == pytest.approx([0.0, 0.2, 0.4], abs=1e-3)
    assert np.isinf(ObstacleMap().distance(np.zeros((2, 2)))).all()


def test_a_hidden_point_inside_a_mapped_obstacle_is_blocked():
    ground = drawn_mask()
    beside = np.array([[0.0, 0.2, 0.0]])             # beside the head: no image shows it
    plain = PerceptionCollisionChecker(K, T_GC, 0.5)
    free, known = plain.point_state(beside, ground)
    assert not known[0]
    m = ObstacleMap()
    m.add_view(np.array([[0.0, 0.15]]), np.array([[0.0, 1.0]]), None, 0.1)
    mapped = PerceptionCollisionChecker(K, T_GC, 0.5, hidden_obstacles=m.blocked)
    free, known = mapped.point_state(beside, ground)
    assert known[0] and not free[0]
    # a point the current image shows is the image's, whatever the map holds
    ahead = np.array([[0.5, 0.0, 0.0]])
    m.add_view(np.array([[0.45, 0.0]]), np.array([[1.0, 0.0]]), None, 0.1)
    mapped = PerceptionCollisionChecker(K, T_GC, 0.5, hidden_obstacles=m.blocked)
    assert mapped.point_state(ahead, ground)[0][0]


def test_the_ros_loop_refuses_the_simulators_truth_map():
    from snake_autonomy.planning.rectilinear.nav_loop import NavLoop
    cfg = dataclasses.replace(CFG, map=MapParams(source="truth"))
    with pytest.raises(ValueError, match="map.source: truth"):
        NavLoop(cfg, 0.09, perception=lambda image: image)


def test_a_run_returns_its_map_and_draws_it(tmp_path):
    """The first replans of world 6 (start facing the cylinder on the start-goal line, 0.72 m ahead of
    the camera): the map holds that cylinder's near side; the run's top view is written with it."""
    from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
    world = random_corridor(6)
    result = NavRun(NavRunSpec(world, seed=7, time_limit_s=25.0, keep_frames=False)).run()
    geom = result.obstacle_map
    assert geom is not None and geom.area > 0
    ahead = world.obstacles[0]                       # (0.78, 0.02), radius 0.06
    assert geom.contains(Point(ahead.x_m - ahead.radius_m + 0.01, ahead.y_m))
    result.write(tmp_path / "run")
    assert (tmp_path / "run" / "topview.png").stat().st_size > 10000


def test_a_views_prior_is_not_laid_on_the_floor_it_shows_beside_the_cylinder():
    pts, dirs, floor = view_on_floor(drawn_mask(discs=[CYL]), K.K(), T_GC, max_range_m=1.5, column_step_px=4,
                                     edge_px=6)
    beside = np.array([[0.6, 0.09], [0.6, -0.09], [0.62, 0.12]])   # floor the view shows, 3-6 cm off the side
    far_side = np.array([[0.65, 0.0], [0.63, 0.045]])             # no view shows these
    old, new = ObstacleMap(), ObstacleMap()
    old.add_view(pts, dirs, floor, 0.1)
    new.add_view(pts, dirs, floor, 0.1, priors_off_own_floor=True)
    assert old.blocked(beside).all() and not new.blocked(beside).any()
    assert old.blocked(far_side).all() and new.blocked(far_side).all()
    lo, hi = new.geometry().bounds[1], new.geometry().bounds[3]
    assert -0.08 < lo < -CYL[2] + 0.005 and CYL[2] - 0.005 < hi < 0.08   # the side within 2 cm
    # a later view's floor still clears an earlier view's disc, with or without the option
    _, _, open_floor = view_on_floor(drawn_mask(), K.K(), T_GC, 1.5)
    new.add_view(np.zeros((0, 2)), np.zeros((0, 2)), open_floor, 0.1, priors_off_own_floor=True)
    assert not new.blocked(far_side).any()
