"""Issue 13 round 20: how COBRA's body really moves at a small curvature, measured with the gait map's
own instrument (runs/gait_map.py simulate_point: the C++ driver's rectilinear gait, nav runs' flat
belly, the centroid of the body's frames over 4 gait cycles, in base_link's frame).

The planner's unicycle says the head moves along its heading and turns at omega_per_kappa * kappa
(config/nav.yaml follower: 0.00923 rad/s per 1/m, a line through 0 fitted over kappa 0..2). Below
about 0.4 /m COBRA does not turn at all: the bent body translates along the tangent of its MIDDLE,
which lies kappa * L/2 to the right of the head's heading for a left bend (L/2 = 0.755 m: 15 deg at
0.35 /m). A small left correction moves the whole robot to the right of where the head points.
Round 20's trace of the contact run mono world 4 seed 8 (links 4-5 on a cylinder the head passed
0.09 m off, on its right): the swing guard held kappa at +0.36 /m for 40 s to keep the head off that
cylinder, the heading stayed at 24-27 deg and the body crawled along 8-9 deg, into it.

`snake_autonomy gait-map --robot cobra --driver-gait rectilinear --amplitudes 0.02 --wavelength 1.0
--kappas 0 0.25 0.35 0.5 0.75 1 2 --flat-belly 0.8 --engine serial --out DIR` (6 s) measured:
omega -0.028 / +0.010 / +0.112 / +0.364 / +0.496 / +1.072 deg/s at kappa 0.25 / 0.35 / 0.5 / 0.75 /
1 / 2 (the line: 0.13 / 0.19 / 0.26 / 0.40 / 0.53 / 1.06); the centroid moving -10.3 / -14.9 / -19.7
/ -28.5 / -37.2 / -66.2 deg off the head's heading against the middle's tangent -10.8 / -15.1 /
-21.6 / -32.4 / -43.3 / -86.5."""
import dataclasses
import math

import numpy as np
import pytest
from shapely.geometry import Point

from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from snake_autonomy.runs.gait_map import gait_map_points, simulate_point
from test_nav_planning import CFG, K, T_GC, drawn_mask
from test_nav_round11 import COBRA

OMEGA_PER_KAPPA = 0.00923      # config/nav.yaml follower.omega_per_kappa (rad/s per 1/m)
HALF_LENGTH_M = 0.755          # COBRA: (head 0.1565 + 11 x 0.123) / 2, body_model.BodyGeometry.of_robot


@pytest.fixture(scope="module")
def points():
    pts = gait_map_points("cobra", "rectilinear", [0.02], [0.35, 1.0], wavelength_m=1.0,
                          flat_belly_fraction=0.8, driver_gait="rectilinear")
    return {p.kappa_per_m: simulate_point(p) for p in pts}


def test_half_length_is_cobras():
    from snake_autonomy import _core
    from snake_autonomy.planning.rectilinear.body_model import BodyGeometry
    from snake_autonomy.cli.nav import robot_yaml
    body = BodyGeometry.of_robot(_core.RobotModel.from_yaml(str(robot_yaml("cobra"))))
    assert body.half_length_m == pytest.approx(HALF_LENGTH_M, abs=1e-3)


def test_cobra_does_not_turn_below_about_0_4_per_m(points):
    """At 0.35 /m the heading turns less than a tenth of what the follower's line predicts; at 1 /m
    the line holds (within 15 %): a dead band, not a smaller slope."""
    slow, fast = points[0.35]["xi_w_rad_s"], points[1.0]["xi_w_rad_s"]
    assert abs(slow) < 0.1 * OMEGA_PER_KAPPA * 0.35, slow
    assert fast == pytest.approx(OMEGA_PER_KAPPA * 1.0, rel=0.15)


def test_at_a_small_curvature_the_body_moves_along_its_middles_tangent(points):
    """At 0.35 /m (bent left) the centroid moves within 2 deg of the middle's tangent, 15 deg right
    of the head's heading, at nearly the straight gait's speed: the robot side-steps to the right
    of where its head points instead of turning left."""
    p = points[0.35]
    moving = math.degrees(math.atan2(p["xi_y_m_s"], p["xi_x_m_s"]))
    tangent = -math.degrees(0.35 * HALF_LENGTH_M)
    assert moving == pytest.approx(tangent, abs=2.0)
    assert moving < -12.0
    assert math.hypot(p["xi_x_m_s"], p["xi_y_m_s"]) > 0.006


def planner_with(obstacle, kappa_per_m, guard_m=0.2, dead_band=0.35, keep_centroid=False, tail_m=0.0, **keys):
    """COBRA at the origin heading +x, bent to kappa_per_m, one disc (x, y, r) in the obstacle map;
    by default the middle kept, no tail or body guard and the crawl guard forcing (round 21's keys
    off), as the crawl guard's single runs were measured. keys: further sampler keys."""
    round21_off = dict(swing_guard_body=False, crawl_blocked_backs_off=False, crawl_guard_forces=True)
    sp = dataclasses.replace(CFG.sampler, swing_guard_m=0.2, crawl_guard_m=guard_m,
                             crawl_dead_band_per_m=dead_band, reshape_keeps_centroid=keep_centroid,
                             swing_guard_tail_m=tail_m, **{**round21_off, **keys})
    p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
    p.obstacle_map = ObstacleMap(Point(obstacle[:2]).buffer(obstacle[2], 32))
    p.follower._kappa = kappa_per_m
    return p


def swing_bounds(p, T_world_g=None):
    """The swing guard's bounds of planner p in open floor at the origin (T_world_g: the ground frame
    in the world, which round 21's body guard needs)."""
    return p._swing_bounds(p._checker(T_GC, np.eye(4), p.sampler_params.swing_obstacle_depth_m), drawn_mask(),
                           T_world_g)


def crawl_bounds(obstacle, kappa_per_m, **kw):
    """(the swing guard's bounds, the crawl guard's)."""
    p = planner_with(obstacle, kappa_per_m, **kw)
    swing = swing_bounds(p)
    return swing, p._crawl_bounds(swing, np.eye(4))


def test_the_crawl_guard_forces_a_turn_away_when_the_held_curvature_crawls_into_the_map():
    """Bent left at 0.36 /m (inside the dead band) the body moves along its middle's tangent, 15.6 deg
    right of the head's heading; a cylinder 0.5 m behind the head, 3 cm below the body's side, is in
    its way: the current kappa is not allowed, the nearest that is (0.61 /m: the middle turns left) is
    forced. With the linear turn rate of the follower (no dead band) the middle would curve away at
    0.36 /m and it would pass; with the guard off the swing guard's bounds stand."""
    kmax = CFG.follower.kappa_max_per_m
    swing, crawl = crawl_bounds((-0.5, -0.11, 0.08), 0.36)
    assert swing == pytest.approx((-kmax, kmax))
    assert crawl == pytest.approx((0.61, kmax))
    assert crawl_bounds((-0.5, -0.11, 0.08), 0.36, dead_band=0.0)[1] == pytest.approx((0.36, kmax))
    # mirrored: bent right beside a cylinder on the left
    assert crawl_bounds((-0.5, 0.11, 0.08), -0.36)[1] == pytest.approx((-kmax, -0.61))
    # the same cylinder 0.14 m further off: the current kappa passes; only a hard right turn is barred
    lo, hi = crawl_bounds((-0.5, -0.25, 0.08), 0.36)[1]
    assert -kmax < lo < 0.0 and hi == pytest.approx(kmax)
    assert crawl_bounds((-0.5, -0.8, 0.08), 0.36)[1] == pytest.approx((-kmax, kmax))


def test_the_replan_hands_the_crawl_guards_bounds_to_the_follower_and_says_so():
    p = planner_with((-0.5, -0.11, 0.08), 0.36)
    r = p.replan(0.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0), None)
    assert r.path_world is not None
    assert "(crawl guard)" in r.reason and "+0.61..+2.00" in r.reason, r.reason
    assert p.follower._bounds == pytest.approx((0.61, 2.0))
    off = planner_with((-0.5, -0.11, 0.08), 0.36, guard_m=0.0)
    r = off.replan(0.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0), None)
    assert "crawl guard" not in r.reason and off.follower._bounds == pytest.approx((-2.0, 2.0))


def test_the_maps_distance():
    m = ObstacleMap(Point(1.0, 0.0).buffer(0.1, 64))
    d = m.distance(np.array([[1.0, 0.0], [1.3, 0.0], [1.0, -0.5]]))
    assert d == pytest.approx([0.0, 0.2, 0.4], abs=1e-3)
    assert np.isinf(ObstacleMap().distance(np.zeros((2, 2)))).all()


@pytest.mark.parametrize("key", ["crawl_guard_m", "crawl_dead_band_per_m", "crawl_margin_m"])
def test_the_crawl_guards_keys_are_validated(key):
    with pytest.raises(NavConfigError, match=rf"sampler.{key}: must be >= 0, got -0.1"):
        NavConfig.from_dict({"sampler": {key: -0.1}})


def test_cobra_reshapes_about_its_centroid_not_its_middle():
    """Straight to 1 /m (runs/turn_sweep.py reshape_step, through the C++ driver): measured head +0.172,
    tail +0.197 m to the inside, the frames at the middle -0.063..-0.075 m to the OUTSIDE, the
    centroid +0.029 m. body_model's middle-fixed model says +0.285 at both ends and 0 at the middle;
    keeping the centroid, +0.19 and -0.095. About 4 s."""
    from snake_autonomy.runs.turn_sweep import reshape_step
    r = reshape_step(1.0)
    assert abs(r.centroid_m) < 0.04
    mid = r.lateral_m[len(r.lateral_m) // 2 - 1:len(r.lateral_m) // 2 + 2]
    assert (mid < -0.04).all(), r.lateral_m
    assert 0.1 < r.lateral_m[0] < 0.25 and 0.1 < r.lateral_m[-1] < 0.25, r.lateral_m


def test_body_poses_keeping_the_centroid():
    """The model of the test above (body_model.body_poses keep_centroid): from straight to 1 /m the
    centroid stays, the middle goes (1 - sin(u) / u) / kappa = 0.093 m to the outside (u = 0.755) and
    the ends (1 - cos(u)) / kappa - 0.093 = 0.179 m to the inside; without it the middle stays."""
    from snake_autonomy.planning.rectilinear.body_model import body_poses
    middle = (0.0, 0.0, 0.0)
    now = body_poses(middle, 0.0, 0.0, HALF_LENGTH_M, 0.01)[-1]
    kept = body_poses(middle, 0.0, 1.0, HALF_LENGTH_M, 0.01, keep_centroid=True)
    about_middle = body_poses(middle, 0.0, 1.0, HALF_LENGTH_M, 0.01)[-1]
    new = kept[-1]
    assert new[:, :2].mean(axis=0) == pytest.approx(now[:, :2].mean(axis=0), abs=1e-9)
    i = len(new) // 2
    u = HALF_LENGTH_M
    assert new[i, 1] == pytest.approx(-(1 - math.sin(u) / u), abs=2e-3)
    assert new[-1, 1] == pytest.approx((1 - math.cos(u)) - (1 - math.sin(u) / u), abs=2e-3)
    assert about_middle[i, 1] == pytest.approx(0.0, abs=1e-9)
    assert about_middle[-1, 1] == pytest.approx(1 - math.cos(u), abs=2e-3)
    # every intermediate shape keeps it too
    for shape in kept:
        assert shape[:, :2].mean(axis=0) == pytest.approx(now[:, :2].mean(axis=0), abs=1e-9)


def test_reshape_keeps_centroid_is_validated():
    with pytest.raises(NavConfigError, match=r"sampler.reshape_keeps_centroid: must be true or false, got 'yes'"):
        NavConfig.from_dict({"sampler": {"reshape_keeps_centroid": "yes"}})


def test_round_20_and_21_settings_in_the_nav_configs():
    """nav.yaml (COBRA): the tail guard on (round 19's 12-link setting, round 20); round 21: reshaping
    about the centroid with the body guard, the crawl guard and backing off a blocked crawl, measured
    at 20 worlds x 5 seeds (README round 21). The 12-link robot keeps round 19's settings (not
    measured with them)."""
    from snake_autonomy.planning.rectilinear.config import nav_config_path
    cobra, chang = NavConfig.from_yaml(), NavConfig.from_yaml(nav_config_path("chang_rectilinear"))
    ftl = NavConfig.from_yaml(nav_config_path("follow_the_leader"))
    assert cobra.sampler.swing_guard_tail_m == chang.sampler.swing_guard_tail_m == pytest.approx(0.2)
    assert cobra.sampler.reshape_keeps_centroid and cobra.sampler.swing_guard_body
    assert cobra.sampler.crawl_guard_m == pytest.approx(0.2) and cobra.sampler.crawl_blocked_backs_off
    assert not cobra.sampler.crawl_guard_forces
    assert cobra.sampler.crawl_dead_band_per_m == pytest.approx(0.35)
    for other in (chang, ftl):
        s = other.sampler
        assert not (s.reshape_keeps_centroid or s.swing_guard_body or s.crawl_blocked_backs_off)
        assert s.crawl_guard_m == 0.0


def test_with_the_centroid_kept_the_map_guard_covers_the_middle():
    """Reshaping about the centroid moves the middle (1 - sin(u)/u)/kappa ~ 0.095 m per 1/m to the
    outside of the bend; the swing guard watched the front 0.2 m (views) and, round 19, the last
    swing_guard_tail_m (map). COBRA depth world 3 seed 0 (centroid, tail 0.2 m): link 5 swung onto
    the cylinder it was passing when the body bent away from it. A disc in the map 0.15 m left of
    the straight body's middle: bending right (its outside is the left) is bounded at -0.25 /m
    (0.024 m + the 0.125 m reach clears it, -0.5 /m's 0.047 m does not) with swing_guard_tail_m 1.5 m
    (the whole body behind the front; measured on 100 runs, not kept: README round 20); with 0.2 m or
    with the middle kept it is not."""
    def bounds(keep, tail_m):
        return swing_bounds(planner_with((-HALF_LENGTH_M, 0.2, 0.05), 0.0, guard_m=0.0, keep_centroid=keep,
                                         tail_m=tail_m))

    kmax = CFG.follower.kappa_max_per_m
    assert bounds(True, 1.5) == pytest.approx((-0.25, kmax))
    assert bounds(True, 0.2) == pytest.approx((-kmax, kmax))
    assert bounds(False, 1.5) == pytest.approx((-kmax, kmax))


def body_guarded(obstacle, kappa_per_m, on=True):
    """The swing guard's bounds with the centroid kept, the tail guard 0.2 m and round 21's body guard."""
    p = planner_with(obstacle, kappa_per_m, guard_m=0.0, keep_centroid=True, tail_m=0.2, swing_guard_body=on)
    return swing_bounds(p, np.eye(4))


def test_round_21_body_guard_keeps_the_middle_off_the_map():
    """Round 21 (sampler.swing_guard_body): the stations between the front and the tail guard keep
    their distance to the map's obstacles: at least the crawl guard's clearance (half the body's
    0.09 m + crawl_margin_m 0.02 = 0.065 m), or what they have now. Reshaping about the centroid moves
    the middle (1 - sin(u)/u)/kappa to the outside (u = 0.755 kappa). The disc of the test above,
    0.15 m left of the middle: bending right is bounded at -0.75 /m (the middle 0.070 m to the left
    keeps 0.080 m; at -1 /m 0.092 m, leaving 0.058); the guard off, it is not."""
    kmax = CFG.follower.kappa_max_per_m
    assert body_guarded((-HALF_LENGTH_M, 0.2, 0.05), 0.0) == pytest.approx((-0.75, kmax))
    assert body_guarded((-HALF_LENGTH_M, 0.2, 0.05), 0.0, on=False) == pytest.approx((-kmax, kmax))
    # 0.1 m off: -0.25 /m keeps 0.076 m, -0.5 /m 0.053 m
    assert body_guarded((-HALF_LENGTH_M, 0.15, 0.05), 0.0) == pytest.approx((-0.25, kmax))
    # 0.07 m off: -0.25 /m would leave 0.046 m; it may not come nearer, it may go away
    assert body_guarded((-HALF_LENGTH_M, 0.12, 0.05), 0.0) == pytest.approx((0.0, kmax))
    # mirrored: a disc on the right bounds bending left
    assert body_guarded((-HALF_LENGTH_M, -0.15, 0.05), 0.0) == pytest.approx((-kmax, 0.25))


def test_round_21_body_guard_needs_the_world_frame_and_is_validated():
    p = planner_with((-HALF_LENGTH_M, 0.15, 0.05), 0.0, guard_m=0.0, keep_centroid=True, tail_m=0.2,
                     swing_guard_body=True)
    assert swing_bounds(p) == pytest.approx((-CFG.follower.kappa_max_per_m, CFG.follower.kappa_max_per_m))
    with pytest.raises(NavConfigError, match=r"sampler.swing_guard_body: must be true or false, got 1"):
        NavConfig.from_dict({"sampler": {"swing_guard_body": 1}})


def test_round_21_when_every_allowed_curvature_crawls_into_the_map_the_robot_backs_off():
    """Round 21 (sampler.crawl_blocked_backs_off). Mono world 4 seed 8 (round 21's trace): the swing
    guard pinned kappa at +0.36 /m for 30 s (the head beside a cylinder on its right, the middle's
    swing to the right when bending further left), so the crawl guard had nothing to choose and the
    body side-stepped into the cylinder. The crawl guard now says so (None) and the replan backs off
    (the reverse gait side-steps the other way) when the tail's track is clear."""
    p = planner_with((-0.5, -0.11, 0.08), 0.36)
    assert p._crawl_bounds((0.36, 0.36), np.eye(4)) is None
    assert planner_with((-0.5, -0.8, 0.08), 0.36)._crawl_bounds((0.36, 0.36), np.eye(4)) == (0.36, 0.36)

    def replan(backs_off):
        p = planner_with((-0.5, -0.11, 0.08), 0.36, crawl_blocked_backs_off=backs_off)
        p.follower.params = dataclasses.replace(p.follower.params, back_off=True)
        p._swing_bounds = lambda *a, **k: (0.36, 0.36)          # pinned, as in the trace
        return p, p.replan(0.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0), None)

    p, r = replan(True)
    assert r.path_world is None and p.follower.mode == "back_off", r.reason
    assert "all crawl into the map (crawl guard): back off" in r.reason
    p, r = replan(False)
    assert r.path_world is not None and p.follower._bounds == pytest.approx((0.36, 0.36))


def test_round_21_the_crawl_guard_may_back_off_instead_of_forcing_a_curvature():
    """Round 21 (sampler.crawl_guard_forces false): when the current kappa crawls into the map the
    crawl guard forces nothing (None, as when no kappa passes), so the replan backs off. Forcing the
    nearest passing kappa fought the planner's arcs: depth w1 s0 was forced from -0.8 to -2 /m in
    steps, 0.3 m from the goal, while every chosen arc turned left, and circled away to the time limit
    (reached at 183 s without forcing)."""
    kmax = CFG.follower.kappa_max_per_m
    forcing = planner_with((-0.5, -0.11, 0.08), 0.36)
    assert forcing._crawl_bounds((-kmax, kmax), np.eye(4)) == pytest.approx((0.61, kmax))
    p = planner_with((-0.5, -0.11, 0.08), 0.36, crawl_guard_forces=False)
    assert p._crawl_bounds((-kmax, kmax), np.eye(4)) is None
    # the current kappa passing, the bounds narrow as before
    far = planner_with((-0.5, -0.25, 0.08), 0.36, crawl_guard_forces=False)
    lo, hi = far._crawl_bounds((-kmax, kmax), np.eye(4))
    assert -kmax < lo < 0.0 and hi == pytest.approx(kmax)
    with pytest.raises(NavConfigError, match=r"sampler.crawl_guard_forces: must be true or false, got 0"):
        NavConfig.from_dict({"sampler": {"crawl_guard_forces": 0}})
