"""Turning in place when no arc is free (planner._free_turn): a turn is taken only if the body's
reshaping sweeps no seen obstacle and the tightest arc on the turning side is free for the crawl the
gait keeps up while the body turns (sampler.turn_free_m); the turn keeps the side chosen at the
stop's first replan (sampler.turn_keeps_side), so the head does not swing both ways beside an
obstacle; when no turn is possible the robot backs off along its track."""
import dataclasses

import numpy as np
import pytest

from nav_scenes import CFG, COBRA, K, T_GC, WALL, drawn_mask, walled_planner
from snake_autonomy.planning.rectilinear.follower import BACK_OFF, RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from snake_autonomy.planning.rectilinear.sampler import Arc, Selection


def free_turn(free_by_curvature, turn_free_m, turning=1.0, sampler=None):
    """_free_turn on open floor (every reshaping shape free) with candidate arcs whose free
    lengths are given {curvature: free_m}; sampler: the sampler parameters (default: nav.yaml's with
    turn_keeps_side off, the other side tried when the turning side is not free)."""
    sp = dataclasses.replace(sampler or dataclasses.replace(CFG.sampler, turn_keeps_side=False),
                             turn_free_m=turn_free_m)
    p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
    ground = drawn_mask()
    checker = p._checker(T_GC, np.eye(4), sp.obstacle_depth_m)
    arcs = [Arc(c, np.zeros((1, 3)), np.zeros(1), free_m=f) for c, f in free_by_curvature.items()]
    p._turning = turning
    return p._free_turn(checker, ground, Selection(arcs), sp.turn_free_m)


def test_a_turn_needs_its_tightest_arc_free_for_turn_free_m():
    kt = CFG.follower.kappa_turn_per_m
    blocked_left = {-3.0: 0.12, -1.5: 0.1, 0.0: 0.0, 1.5: 0.08, 3.0: 0.0}
    # off: the turning side first, its crawl unchecked
    assert free_turn(blocked_left, 0.0) == pytest.approx(kt)
    # on: the left's tightest arc is 0.00 m free, the right's 0.12 m: turn right
    assert free_turn(blocked_left, 0.05) == pytest.approx(-kt)
    # only the tightest arc on a side counts (left 1.5 /m free 0.08 m does not make up for 3 /m)
    assert free_turn({-3.0: 0.0, 3.0: 0.0, 1.5: 0.3, -1.5: 0.3}, 0.05) is None
    # both sides with room: the turning side first, as before
    assert free_turn({-3.0: 0.06, 3.0: 0.06}, 0.05, turning=-1.0) == pytest.approx(-kt)


def test_a_wall_right_ahead_leaves_no_room_to_turn_the_robot_backs_off():
    # the wall 0.12 m ahead: every arc 0.00 m free after margin_m; the sweep alone would turn
    for turn_free_m, expect in ((0.05, "no turn the body can sweep: back off"), (0.0, "turn in place")):
        sp = dataclasses.replace(CFG.sampler, turn_free_m=turn_free_m)
        fp = dataclasses.replace(CFG.follower, back_off=True, back_off_replans=1)
        p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(fp), COBRA)
        p.replan(0.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), None)            # backs off once
        r = p.replan(10.0, drawn_mask(**WALL), T_GC, (-0.07, 0.0, 0.0), None)
        assert expect in r.reason, (turn_free_m, r.reason)
    # nowhere to back off to (follower.back_off false): a turn the sweep allows, crawl room or not
    sp = dataclasses.replace(CFG.sampler, turn_free_m=0.05)
    fp = dataclasses.replace(CFG.follower, back_off=False)
    p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(fp), COBRA)
    r = p.replan(0.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), None)
    assert p.follower.mode == "turn_in_place" and "turn in place" in r.reason


def test_a_turn_in_place_whose_sweep_hits_a_seen_obstacle_is_not_taken():
    # a disc seen 1.1 m ahead of an earlier pose, now beside the head on the left (y 0.35): bending
    # left swings the head (L^2/8) kappa to the left into it (0.21 m at 0.75 /m, 0.43 m at 1.5 /m)
    p = walled_planner(back_off=False)
    p.replan(0.0, drawn_mask(discs=[(1.1, 0.35, 0.1)]), T_GC, (-1.2, 0.0, 0.0), None)
    r = p.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (2.0, 0.5))   # the goal on the left
    assert r.path_world is None
    assert p.follower.mode == "turn_in_place" and p.follower.turn_direction == -1.0, r.reason
    assert "kappa -1.50" in r.reason
    # without the disc the goal's side is taken
    q = walled_planner(back_off=False)
    r = q.replan(0.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (2.0, 0.5))
    assert q.follower.turn_direction == 1.0 and "kappa +1.50" in r.reason


def test_with_no_turn_the_body_can_sweep_the_robot_backs_off_again():
    p = walled_planner(back_off=True, back_off_replans=1)
    discs = [(1.1, 0.35, 0.1), (1.1, -0.35, 0.1)]             # beside the head on both sides
    p.replan(0.0, drawn_mask(discs=discs), T_GC, (-1.2, 0.0, 0.0), None)
    r1 = p.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), None)
    assert "back off" in r1.reason and p.follower.mode == BACK_OFF           # the first stop backs off
    r2 = p.replan(20.0, drawn_mask(**WALL), T_GC, (-0.07, 0.0, 0.0), None)
    assert "no turn the body can sweep" in r2.reason and p.follower.mode == BACK_OFF
    # one side free: the second stop turns there
    q = walled_planner(back_off=True, back_off_replans=1)
    q.replan(0.0, drawn_mask(discs=discs[:1]), T_GC, (-1.2, 0.0, 0.0), None)
    q.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), None)
    r = q.replan(20.0, drawn_mask(**WALL), T_GC, (-0.07, 0.0, 0.0), None)
    assert q.follower.mode == "turn_in_place" and q.follower.turn_direction == -1.0, r.reason


def keeps_side(on: bool):
    return dataclasses.replace(CFG.sampler, turn_keeps_side=on)


def test_a_turn_never_takes_the_other_side_when_turn_keeps_side():
    kt = CFG.follower.kappa_turn_per_m
    blocked_left = {-3.0: 0.12, -1.5: 0.1, 0.0: 0.0, 1.5: 0.08, 3.0: 0.0}
    # the stop chose left; left has no room to crawl, right has
    assert free_turn(blocked_left, 0.05, turning=1.0, sampler=keeps_side(False)) == pytest.approx(-kt)
    assert free_turn(blocked_left, 0.05, turning=1.0, sampler=keeps_side(True)) is None
    # the chosen side free: turns to it, whichever the flag
    for on in (False, True):
        assert free_turn(blocked_left, 0.05, turning=-1.0, sampler=keeps_side(on)) == pytest.approx(-kt)


def test_nowhere_to_back_off_to_a_turn_may_still_take_the_other_side():
    """Keeping the side falls back to backing off; without back_off (follower.back_off false) the
    planner still turns to whichever side it can sweep rather than blindly to the stop's side."""
    for back_off in (True, False):
        p = walled_planner(back_off=back_off, back_off_replans=1)
        p.sampler_params = dataclasses.replace(p.sampler_params, turn_keeps_side=True)
        p.replan(0.0, drawn_mask(discs=[(1.1, 0.35, 0.1)]), T_GC, (-1.2, 0.0, 0.0), None)   # seen on the left
        r = p.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (2.0, 0.5))        # the goal on the left
        if back_off:            # the first stop backs off; the second cannot sweep left and backs off again
            assert p.follower.mode == "back_off", r.reason
            r = p.replan(20.0, drawn_mask(**WALL), T_GC, (-0.07, 0.0, 0.0), (2.0, 0.5))
            assert p._turning == 1.0 and "no turn the body can sweep: back off" in r.reason, r.reason
        else:
            assert p.follower.mode == "turn_in_place" and "kappa -1.50" in r.reason, r.reason
