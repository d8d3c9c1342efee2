"""Issue 13 round 19: backing off is checked (sampler.back_off_check_m, planner._back_off_clear), and
the shadow behind an obstacle in an old view no longer outvotes the floor newer views show
(sampler.blocked_wins_depth_m).

With no free arc the robot backs off tail first at its body's curvature. Until round 19 nothing
checked where the tail went: the robot's own views and the obstacle map knew the cylinder behind it,
and three of the 12-link robot's four new contact runs of round 18 (map.priors_off_own_floor, seeds
5-9) were the tail backing off into one. At a constant kappa every point of the body moves into the
place of the point behind it; only the tail enters new ground, along the body's circle continued.

The 12-link robot's stops in open floor near the goal (depth world 13 seed 8 at 122 s, mono world 9
seed 8 at 132 s: every arc 0.00 m free) were two points beside the head that one view, 80-110 s old,
showed as non-ground 0.21-0.24 m beyond its ground edge (within obstacle_depth_m 0.25: the floor
hidden behind the cylinder it saw), while later views showed them as floor. blocked_wins (round 10)
let that shadow win; it is there for a classifier missing an obstacle's face in one view."""
import dataclasses

import numpy as np
import pytest
from shapely.geometry import Point

from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from test_nav_body_footprint import shifted
from test_nav_planning import CFG, K, T_GC, drawn_mask
from test_nav_round5 import WALL
from test_nav_round11 import COBRA


def stop_with(obstacle, kappa_per_m=0.0, check_m=0.1):
    """One replan facing a wall right ahead (no free arc) with one disc (x, y, r) in the obstacle map,
    the body bent to kappa_per_m: the follower's mode and the replan's reason."""
    sp = dataclasses.replace(CFG.sampler, back_off_check_m=check_m)
    fp = dataclasses.replace(CFG.follower, back_off=True, back_off_replans=2)
    p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(fp), COBRA)
    if obstacle is not None:
        p.obstacle_map = ObstacleMap(Point(obstacle[:2]).buffer(obstacle[2], 32))
    p.follower._kappa = kappa_per_m
    r = p.replan(0.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), None)
    return p.follower.mode, r.reason


def test_the_tail_does_not_back_off_into_what_the_map_shows():
    # COBRA straight: its tail 1.51 m behind base_link; a cylinder 5-11 cm behind the tail
    assert stop_with(None)[0] == "back_off"
    mode, reason = stop_with((-1.61, 0.0, 0.05))
    assert mode == "turn_in_place" and "the tail's track is blocked" in reason, reason
    # beside the track, further than half the body's checked width (0.045 + 0.08 m): backs off
    assert stop_with((-1.61, 0.25, 0.05))[0] == "back_off"
    # unchecked (0, the default before round 19): backs off into it
    assert stop_with((-1.61, 0.0, 0.05), check_m=0.0)[0] == "back_off"


def test_the_tail_track_follows_the_body_curvature():
    # bent to kappa 1 /m the tail lies on the circle: (sin(-1.51), 1 - cos(-1.51)) = (-0.998, 0.939),
    # moving on along it to (-0.999, 1.039) over 0.1 m
    assert stop_with((-1.61, 0.0, 0.05), kappa_per_m=1.0)[0] == "back_off"
    mode, reason = stop_with((-1.0, 1.06, 0.03), kappa_per_m=1.0)
    assert mode == "turn_in_place", reason
    assert stop_with((-1.0, 1.06, 0.03), kappa_per_m=-1.0)[0] == "back_off"


def test_back_off_check_m_is_validated():
    with pytest.raises(NavConfigError, match=r"sampler.back_off_check_m: must be >= 0, got -0.1"):
        NavConfig.from_dict({"sampler": {"back_off_check_m": -0.1}})


def test_an_old_views_shadow_yields_to_floor_another_view_shows_its_face_does_not():
    # a view 1 m back shows a disc 0.6 m ahead of it: the disc spans x -0.46..-0.34 in the current
    # frame (hidden now, behind the camera); the floor 0.2 m beyond its face is in its shadow
    face, shadow = np.array([[-0.45, 0.0, 0.0]]), np.array([[-0.26, 0.0, 0.0]])
    seen, floor, now = drawn_mask(discs=[(0.6, 0.0, 0.06)]), drawn_mask(), drawn_mask()

    def free(depth_m, views):
        c = PerceptionCollisionChecker(K, T_GC, 0.5, blocked_wins=True, blocked_wins_depth_m=depth_m)
        for ground, x in views:
            c.add_view(ground, shifted(x), obstacle_depth_m=0.25)
        return [bool(c.point_state(p, now)[0][0]) for p in (face, shadow)]

    both = [(floor, -0.7), (seen, -1.0)]            # a newer view showed floor at both points
    assert free(float("inf"), both) == [False, False]          # round 10: any obstacle wins
    assert free(0.1, both) == [False, True]                    # round 19: only the face does
    assert free(0.1, [(seen, -1.0)]) == [False, False]         # no view shows floor there: blocked


def test_the_planner_passes_blocked_wins_depth_m_and_it_is_validated():
    sp = dataclasses.replace(CFG.sampler, blocked_wins_depth_m=0.1)
    p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
    assert p._checker(T_GC, np.eye(4), sp.obstacle_depth_m).blocked_wins_depth_m == pytest.approx(0.1)
    with pytest.raises(NavConfigError, match=r"sampler.blocked_wins_depth_m: must be >= 0, got -1"):
        NavConfig.from_dict({"sampler": {"blocked_wins_depth_m": -1}})


def test_the_tail_guard_keeps_the_tails_swing_off_what_the_map_holds():
    """Round 19 option (sampler.swing_guard_tail_m): bending to kappa swings the tail (L^2/8) kappa
    to the inside of the turn, as far as the head (body_model.py); the swing guard watched only the
    body's first 0.2 m. The 12-link robot's tail touched the cylinder it had passed 0.7 m earlier
    while the head turned left (depth world 4 seed 7). A cylinder in the map 0.25-0.45 m to the left
    of COBRA's straight tail: bending left is bounded, bending right is not."""
    def bounds(tail_m, obstacle=(-1.45, 0.35, 0.1)):
        sp = dataclasses.replace(CFG.sampler, swing_guard_tail_m=tail_m, reshape_keeps_centroid=False)   # round 19's
        p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
        p.obstacle_map = ObstacleMap(Point(obstacle[:2]).buffer(obstacle[2], 32))
        return p._swing_bounds(p._checker(T_GC, np.eye(4), sp.swing_obstacle_depth_m), drawn_mask())

    kmax = CFG.follower.kappa_max_per_m
    assert bounds(0.0) == pytest.approx((-kmax, kmax))
    lo, hi = bounds(0.2)
    assert lo == pytest.approx(-kmax) and hi == pytest.approx(0.25)   # 0.285 m per 1/m + 0.125 m reach
    # the same cylinder beside the middle (which does not swing) bounds nothing
    assert bounds(0.2, (-0.75, 0.2, 0.05)) == pytest.approx((-kmax, kmax))


def test_round_19_settings_in_the_nav_configs():
    """nav.yaml (COBRA) and nav_chang_rectilinear.yaml: measured at 20 worlds x 5 seeds x both seed sets
    (README round 19)."""
    from snake_autonomy.planning.rectilinear.config import nav_config_path
    cobra, chang = NavConfig.from_yaml(), NavConfig.from_yaml(nav_config_path("chang_rectilinear"))
    assert cobra.map.priors_off_own_floor and chang.map.priors_off_own_floor
    assert cobra.sampler.blocked_wins_depth_m == chang.sampler.blocked_wins_depth_m == pytest.approx(0.1)
    assert cobra.sampler.back_off_check_m == pytest.approx(0.1)
    assert chang.sampler.back_off_check_m == pytest.approx(0.15)
    assert cobra.sampler.turn_free_m == pytest.approx(0.05) and chang.sampler.turn_free_m == pytest.approx(0.1)
    assert chang.sampler.swing_guard_tail_m == pytest.approx(0.2)   # COBRA too since round 20 (test_nav_round20)
