"""Backing off when no arc is free (follower.back_off, gaits.yaml rectilinear_reverse): the robot
crawls tail first along its track at the body's curvature, resumes only with resume_free_m free
ahead, and does not back off when the tail's track meets what the obstacle map holds
(sampler.back_off_check_m): at a constant kappa only the tail enters new ground, along the body's
circle continued."""
import dataclasses

import numpy as np
import pytest
from shapely.geometry import Point

from nav_scenes import CFG, COBRA, K, T_GC, WALL, drawn_mask
from snake_autonomy.planning.rectilinear.follower import BACK_OFF, RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.planner import NavPlanner


def test_with_back_off_no_free_arc_backs_off_along_the_track_with_kappa_held():
    fp = dataclasses.replace(CFG.follower, back_off=True, kappa_rate_per_m_s=0.0)
    planner = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(fp))
    planner.follower._kappa = 0.4                             # the body's current curvature
    wall = drawn_mask(boxes=[(0.12, 0.6, -1.0, 1.0)])         # a wall right ahead
    r = planner.replan(0.0, wall, T_GC, (0.0, 0.0, 0.0), (2.0, 0.0))
    assert r.path_world is None and "back off" in r.reason
    cmd = planner.command(0.0, (0.0, 0.0, 0.0))
    assert cmd.mode == BACK_OFF and cmd.kappa_per_m == pytest.approx(0.4)
    # the unicycle prediction moves tail first, turning back along the same circle
    cmd = planner.command(10.0, None)
    x, y, th = planner.follower.pose
    assert x < -0.5 * fp.speed_m_s * 10.0
    assert th < 0.0                                          # kappa > 0 backwards: clockwise
    # a free arc again: following
    r = planner.replan(10.0, drawn_mask(), T_GC, (x, y, th), (2.0, 0.0))
    assert r.path_world is not None and planner.command(10.5, (x, y, th)).mode == "follow"


def test_without_back_off_no_free_arc_still_turns_in_place():
    planner = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(dataclasses.replace(CFG.follower,
                                                                                           back_off=False)))
    planner.replan(0.0, drawn_mask(boxes=[(0.12, 0.6, -1.0, 1.0)]), T_GC, (0.0, 0.0, 0.0), (2.0, 0.0))
    assert planner.command(0.0, (0.0, 0.0, 0.0)).mode == "turn_in_place"


def test_the_reverse_gait_is_the_forward_wave_travelling_the_other_way(root):
    import yaml
    gaits = yaml.safe_load((root / "config" / "gaits.yaml").read_text())["gaits"]
    fwd, rev = gaits["rectilinear"], gaits["rectilinear_reverse"]
    assert rev["pitch"]["lag_deg"] == pytest.approx(-fwd["pitch"]["lag_deg"])
    assert rev["pitch"]["amplitude_deg"] == fwd["pitch"]["amplitude_deg"]
    assert rev["frequency_hz"] == fwd["frequency_hz"] and rev["steering"] == "curvature"


def test_after_no_free_arc_the_robot_resumes_only_with_resume_free_m_ahead():
    # arcs to 2 /m: nav.yaml's 3 /m arcs (0.33 m radius) curl round before the wall
    sp = dataclasses.replace(CFG.sampler, resume_free_m=0.6, known_free_m=0.3, body_clearance_m=0.0,
                             max_curvature_per_m=2.0)
    fp = dataclasses.replace(CFG.follower, back_off=True)
    planner = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(fp))
    near = drawn_mask(boxes=[(0.12, 0.6, -1.0, 1.0)])          # a wall 0.12 m ahead: nothing free
    assert planner.replan(0.0, near, T_GC, (0.0, 0.0, 0.0), None).path_world is None
    mid = drawn_mask(boxes=[(0.55, 0.9, -1.0, 1.0)])           # backed off: 0.55 m, free ~0.35 m
    r = planner.replan(10.0, mid, T_GC, (0.0, 0.0, 0.0), None)
    assert max(a.free_m for a in r.selection.arcs) >= sp.min_free_m
    assert r.path_world is None                                 # not enough to resume: back on
    far = drawn_mask(boxes=[(1.0, 1.2, -1.0, 1.0)])
    assert planner.replan(20.0, far, T_GC, (0.0, 0.0, 0.0), None).path_world is not None
    # once following, min_free_m is enough again
    assert planner.replan(30.0, mid, T_GC, (0.0, 0.0, 0.0), None).path_world is not None


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
    # unchecked (0, the default): backs off into it
    assert stop_with((-1.61, 0.0, 0.05), check_m=0.0)[0] == "back_off"


def test_the_tail_track_follows_the_body_curvature():
    # bent to kappa 1 /m the tail lies on the circle: (sin(-1.51), 1 - cos(-1.51)) = (-0.998, 0.939),
    # moving on along it to (-0.999, 1.039) over 0.1 m
    assert stop_with((-1.61, 0.0, 0.05), kappa_per_m=1.0)[0] == "back_off"
    mode, reason = stop_with((-1.0, 1.06, 0.03), kappa_per_m=1.0)
    assert mode == "turn_in_place", reason
    assert stop_with((-1.0, 1.06, 0.03), kappa_per_m=-1.0)[0] == "back_off"


def test_the_follower_reports_the_curvature_its_recovery_steers_to():
    f = RecedingHorizonFollower()
    assert f.recovery_kappa() is None
    f.back_off_now(0.7)
    assert f.recovery_kappa() == pytest.approx(0.7)
    f.back_off_now()                                    # the body's curvature held: the last commanded one
    assert f.recovery_kappa() == pytest.approx(f.kappa_per_m)
    f.stop_and_turn(-1.0, 2.5)
    assert f.recovery_kappa() == pytest.approx(-2.5)
    f.set_path(np.zeros((2, 2)), 0.0)
    assert f.recovery_kappa() is None
