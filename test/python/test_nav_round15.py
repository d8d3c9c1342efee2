"""Issue 13 round 15: a map of the obstacles the views showed (obstacle_map.py: each face grown into a
prior disc behind it) answers for the points no image shows, and a route on it (route.py) gives the
goal bias a cost to go, so the robot keeps out of the funnels between obstacles nearer than its
checked footprint."""
import dataclasses
import math

import numpy as np
import pytest
from shapely.geometry import Point

from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.obstacle_map import MapParams, ObstacleMap, view_on_floor
from snake_autonomy.planning.rectilinear.route import Route
from snake_autonomy.planning.rectilinear.sampler import TrajectorySampler
from snake_autonomy.runs.nav_experiment import random_corridor
from test_nav_planning import CFG, K, T_GC, drawn_mask

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


def test_the_route_goes_round_world_6s_funnel_not_through_it():
    world = random_corridor(6)                       # three cylinders, gaps 0.26-0.30 m
    geom = ObstacleMap.from_world(world.obstacles).geometry()
    route = Route(inflation_m=0.25)
    route.update(geom, world.start[:2], world.goal)
    clearance = min(ob.distance_m(x, y) for x, y in route.path for ob in world.obstacles)
    assert clearance > 0.25 - route.cell_m, clearance
    # the cost to go: the funnel's mouth (between the cylinders) costs more than going round
    funnel, round_ = np.array([[0.55, 0.0]]), np.array([[0.3, 0.7]])
    assert route.cost_to_go(funnel)[0] > route.cost_to_go(round_)[0]
    # no obstacles: the straight line, cost = distance
    route.update(None, (0.0, 0.0), (1.0, 0.0))
    assert route.cost_to_go(np.array([[0.0, 1.0]]))[0] == pytest.approx(math.sqrt(2.0))


def test_the_goal_bias_follows_the_cost_to_go_when_a_route_gives_one():
    sp = CFG.sampler
    sampler = TrajectorySampler(PerceptionCollisionChecker(K, T_GC, 0.5), sp, 0.25)
    ground = drawn_mask()
    goal = (1.0, 0.0)
    straight = sampler.select(ground, goal)
    assert straight.arc.curvature_per_m == 0.0
    # a route that says "the way to the goal is on the left" (everything right of y = 0.2 is dear)
    ctg = lambda xy: np.hypot(xy[:, 0] - goal[0], xy[:, 1] - goal[1]) + 10.0 * (xy[:, 1] < 0.2)
    left = sampler.select(ground, goal, cost_to_go=ctg)
    assert left.arc.curvature_per_m > 0


def test_the_map_section_is_checked_and_named():
    base = {"map": {"source": "walls", "prior_radius_m": -0.1, "edge_px": 2.5, "route": 1}}
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_dict(base)
    text = str(e.value)
    for part in ("map.source: expected one of none, faces, truth, got 'walls'", "map.prior_radius_m: must be > 0",
                 "map.edge_px: must be an integer", "map.route: must be true or false, got 1"):
        assert part in text, text
    with pytest.raises(NavConfigError, match="route: true needs a map"):
        NavConfig.from_dict({"map": {"route": True}})
    assert MapParams().validate() == []


def test_the_ros_loop_refuses_the_simulators_truth_map():
    from snake_autonomy.planning.rectilinear.nav_loop import NavLoop
    cfg = dataclasses.replace(CFG, map=MapParams(source="truth"))
    with pytest.raises(ValueError, match="map.source: truth"):
        NavLoop(cfg, 0.09, perception=lambda image: image)


def test_cobra_goes_round_world_6_instead_of_into_its_funnel(tmp_path, root):
    """Random world 6 (three cylinders, gaps 0.26-0.30 m: narrower than COBRA's 0.5 m checked
    footprint), seed 7, depth. Without the map (round 14's planner) COBRA drove into the funnel,
    stopped, and touched at 103 s (round 14: 75 episodes over seeds 7-9). With config/nav.yaml's map
    and route it went round the cluster: the goal at 286 s, no contact (~25 s wall). The map's priors
    as round 15 laid them: with map.priors_off_own_floor (on since round 19) the gaps look wider in
    the map and this run stops in the funnel (31 stops to 400 s, no contact; README round 19). Both
    runs keep round 20's sampler (round 21's centroid, body and crawl guards: this run reaches the time
    limit, no contact)."""
    from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
    committed = NavConfig.from_yaml().map
    assert (committed.source, committed.route) == ("faces", True)
    off = tmp_path / "off.yaml"
    round20 = ("sampler: {reshape_keeps_centroid: false, swing_guard_body: false, crawl_guard_m: 0.0, "
               "crawl_blocked_backs_off: false}\n")
    off.write_text(f"base: {root / 'config' / 'nav.yaml'}\nmap: {{source: none, route: false}}\n{round20}")
    before = NavRun(NavRunSpec(random_corridor(6), seed=7, time_limit_s=120.0, nav_config=str(off),
                               keep_frames=False)).run()
    assert before.metrics["collisions"] > 0, before.metrics
    own = tmp_path / "round15_map.yaml"
    own.write_text(f"base: {root / 'config' / 'nav.yaml'}\nmap: {{priors_off_own_floor: false}}\n{round20}")
    run = NavRun(NavRunSpec(random_corridor(6), seed=7, time_limit_s=400.0, keep_frames=False, nav_config=str(own)))
    result = run.run()
    assert result.metrics["outcome"] == "success", result.metrics
    # it went round (south of the cluster's lowest cylinder or north of its highest), not between
    ys = result.trajectory[:, 2]
    lows = [ob.y_m - ob.radius_m for ob in random_corridor(6).obstacles]
    highs = [ob.y_m + ob.radius_m for ob in random_corridor(6).obstacles]
    assert ys.min() < min(lows) or ys.max() > max(highs), (ys.min(), ys.max())
    assert all(r.route_world is not None for r in result.replans)


def test_a_rotated_box_is_mapped_by_its_corners():
    from snake_autonomy.sim.world_file import Obstacle
    box = Obstacle("box", 1.0, 0.5, size_m=(0.4, 0.1, 0.3), yaw_deg=90.0)
    assert np.allclose(sorted(box.corners()), sorted([(1.05, 0.7), (0.95, 0.7), (0.95, 0.3), (1.05, 0.3)]))
    m = ObstacleMap.from_world([box])
    assert m.blocked(np.array([[1.0, 0.68], [1.0, 0.32]])).all()        # along its long side, now y
    assert not m.blocked(np.array([[1.15, 0.5], [0.85, 0.5]])).any()


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
