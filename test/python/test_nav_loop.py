"""planner_node's ROS-free logic (planning/rectilinear/nav_loop.py): replans from the latest frame
and pose, hold while waiting, with no free arc and at the goal; the image message conversions. The loop's
rules are the same for either planner: these tests run the perception-space one (no body needed, a
traversability image decides each arc); the layered one's loop: test_nav_layered.py."""
import dataclasses
import math

import numpy as np
import pytest

from snake_autonomy.paths import config_path
from snake_autonomy.planning.rectilinear.config import NavConfig
from snake_autonomy.planning.rectilinear.nav_loop import (ERROR, FOLLOWING, GOAL_REACHED, NO_FREE_ARC, NO_GOAL,
                                                          STALE, WAITING, NavLoop)


PERCEPTION_SPACE = config_path("nav_perception_space.yaml")


def _pose(x, y, th, z=0.045):
    T = np.eye(4)
    T[:2, :2] = [[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]
    T[:3, 3] = (x, y, z)
    return T


def _loop(ground_value, **kw):
    cfg = NavConfig.from_yaml(PERCEPTION_SPACE)
    # the footprint's near field (hidden under the view) counts as free: ask for more than it
    cfg = dataclasses.replace(cfg, sampler=dataclasses.replace(cfg.sampler, min_free_m=0.5))
    k = cfg.intrinsics
    return NavLoop(cfg, 0.09, lambda img: np.full((k.height, k.width), ground_value, bool), **kw), cfg


def _frame(cfg):
    """A depth frame of the camera's size (the test perceptions ignore its values)."""
    return np.zeros((cfg.intrinsics.height, cfg.intrinsics.width), np.float32)


def _feed(loop, cfg, t_s, pose):
    """A fresh pose and frame at t_s."""
    assert loop.on_pose(t_s, pose) is None
    assert loop.on_frame(t_s, _frame(cfg)) is None


def test_open_floor_follows_and_replans_on_the_period():
    loop, cfg = _loop(True, goal_xy=(2.0, 0.0), goal_radius_m=0.1)
    assert loop.tick(0.0).state == WAITING and loop.tick(0.0).hold
    _feed(loop, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    out = loop.tick(0.5)
    assert out.state == FOLLOWING and not out.hold and out.replan is not None
    assert out.replan.path_world is not None and out.replan.path_world[-1, 0] > 0.5
    assert abs(out.kappa_per_m) < 0.1                    # straight ahead to the goal
    assert loop.tick(1.0).replan is None                  # next replan after replan_period_s
    _feed(loop, cfg, 0.5 + cfg.replan_period_s, _pose(0.0, 0.0, 0.0))
    assert loop.tick(0.5 + cfg.replan_period_s).replan is not None
    assert loop.replans == 2


def test_no_free_arc_holds_or_turns():
    loop, cfg = _loop(False, goal_xy=(2.0, 0.0))
    _feed(loop, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    out = loop.tick(0.0)
    assert out.state == NO_FREE_ARC and out.hold and out.replan.path_world is None
    assert "no collision-free arc" in out.message and loop.stops_no_free_arc == 1
    turn, _ = _loop(False, goal_xy=(2.0, 0.0), on_no_free_arc="turn")
    _feed(turn, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    turn.tick(0.0)
    assert turn.on_pose(4.0, _pose(0.0, 0.0, 0.0)) is None
    out = turn.tick(4.0)                                # kappa rate-limited towards kappa_turn_per_m
    assert not out.hold and out.kappa_per_m != 0.0 and not out.backwards
    back, _ = _loop(False, goal_xy=(2.0, 0.0), on_no_free_arc="back_off")
    _feed(back, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    out = back.tick(0.0)
    assert out.state == NO_FREE_ARC and "backing off" in out.message
    assert back.on_pose(4.0, _pose(0.0, 0.0, 0.0)) is None
    out = back.tick(4.0)
    assert not out.hold and out.backwards and out.kappa_per_m == 0.0      # the reverse gait, kappa held


def test_goal_reached_holds_for_good():
    loop, cfg = _loop(True, goal_xy=(1.0, 0.0), goal_radius_m=0.2)
    _feed(loop, cfg, 0.0, _pose(0.9, 0.05, 0.3))
    out = loop.tick(1.0)
    assert out.state == GOAL_REACHED and out.hold
    loop.on_pose(2.0, _pose(0.0, 0.0, 0.0))
    assert loop.tick(2.0).state == GOAL_REACHED


def test_the_loop_stops_the_goal_margin_inside_the_disc():
    """follower.goal_margin_m (the stop's own move, bench/nav_stop_shift): 0.05 m inside a 0.2 m disc;
    never nearer the centre than half the radius."""
    loop, cfg = _loop(True, goal_xy=(1.0, 0.0), goal_radius_m=0.2)
    loop.cfg = cfg = dataclasses.replace(cfg, follower=dataclasses.replace(cfg.follower, goal_margin_m=0.05))
    assert loop.stop_radius_m() == pytest.approx(0.15)
    _feed(loop, cfg, 0.0, _pose(0.83, 0.0, 0.0))          # inside the disc, not the margin
    assert loop.tick(0.5).state != GOAL_REACHED
    _feed(loop, cfg, 1.0, _pose(0.86, 0.0, 0.0))
    assert loop.tick(1.0).state == GOAL_REACHED
    loop.set_goal((1.0, 0.0), 0.06)
    assert loop.stop_radius_m() == pytest.approx(0.03)


def test_without_a_goal_the_loop_holds_until_one_is_set():
    loop, cfg = _loop(True)
    _feed(loop, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    out = loop.tick(0.5)
    assert out.state == NO_GOAL and out.hold and out.message == "no goal: holding"
    assert loop.replans == 0 and loop.distance_to_goal_m() is None
    loop.set_goal((2.0, 0.0), 0.2)
    out = loop.tick(0.6)
    assert out.state == FOLLOWING and not out.hold and out.replan is not None and loop.replans == 1


def test_a_new_goal_ends_goal_reached_and_replans_at_the_next_tick():
    loop, cfg = _loop(True, goal_xy=(1.0, 0.0), goal_radius_m=0.2)
    _feed(loop, cfg, 0.0, _pose(0.95, 0.0, 0.0))
    assert loop.tick(0.5).state == GOAL_REACHED
    loop.set_goal((3.0, 0.0), 0.3)
    assert (loop.goal_xy, loop.goal_radius_m) == ((3.0, 0.0), 0.3)
    out = loop.tick(0.6)                                    # long before replan_period_s: at once
    assert out.state == FOLLOWING and not out.hold and out.replan is not None
    assert loop.distance_to_goal_m() == pytest.approx(2.05)
    loop.set_goal((1.0, 0.1), 0.2)                          # where the robot is: reached at the next tick
    assert loop.tick(0.7).state == GOAL_REACHED


def test_clear_goal_holds_keeping_the_curvature():
    loop, cfg = _loop(True, goal_xy=(1.0, 1.0), goal_radius_m=0.1)
    for t in (0.0, 0.5, 1.0, 1.5):                           # kappa is rate-limited: a few ticks to bend
        _feed(loop, cfg, t, _pose(0.0, 0.0, 0.0))
        moving = loop.tick(t)
    assert not moving.hold and moving.kappa_per_m > 0.0     # turning towards the goal on the left
    loop.clear_goal()
    replans = loop.replans
    for t in (1.6, 5.0):
        out = loop.tick(t)
        assert out.state == NO_GOAL and out.hold and out.kappa_per_m == moving.kappa_per_m
    assert loop.replans == replans


def test_a_bad_goal_is_refused_and_changes_nothing():
    loop, _ = _loop(True, goal_xy=(1.0, 0.0), goal_radius_m=0.2)
    for goal, radius, match in (((float("nan"), 0.0), 0.2, "goal_xy: must be finite"),
                                (("a", 0.0), 0.2, "goal_xy: expected two numbers"),
                                ((1.0, 2.0, 3.0), 0.2, "goal_xy: expected two numbers"),
                                ((2.0, 0.0), 0.0, "goal_radius_m: must be a finite number > 0, got 0.0"),
                                ((2.0, 0.0), float("inf"), "goal_radius_m: .* got inf")):
        with pytest.raises(ValueError, match=match):
            loop.set_goal(goal, radius)
    assert (loop.goal_xy, loop.goal_radius_m) == ((1.0, 0.0), 0.2)


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="on_no_free_arc"):
        _loop(True, on_no_free_arc="spin")
    with pytest.raises(ValueError, match="goal_radius_m"):
        _loop(True, goal_radius_m=0.0)


def test_a_replan_uses_the_pose_at_the_frames_stamp():
    loop, cfg = _loop(True, goal_xy=(2.0, 0.0))
    for k in range(11):
        loop.on_pose(0.1 * k, _pose(0.01 * k, 0.0, 0.0))
    loop.on_frame(0.42, _frame(cfg))
    out = loop.tick(1.0)
    assert out.replan.pose[0] == pytest.approx(0.04)       # the pose of t 0.4, not the latest (0.10)
    assert loop.pose[0] == pytest.approx(0.10)


def test_a_bad_pose_is_refused_counted_and_changes_nothing():
    loop, cfg = _loop(True, goal_xy=(2.0, 0.0))
    _feed(loop, cfg, 1.0, _pose(0.1, 0.0, 0.0))
    nan = _pose(0.1, 0.0, 0.0)
    nan[0, 3] = float("nan")
    sheared = _pose(0.1, 0.0, 0.0)
    sheared[0, 1] = 0.5
    assert "not finite" in loop.on_pose(1.1, nan)
    assert "not a rotation" in loop.on_pose(1.1, sheared)
    assert "beyond" in loop.on_pose(1.1, _pose(1e6, 0.0, 0.0))
    assert "older than the last pose" in loop.on_pose(0.5, _pose(0.2, 0.0, 0.0))
    assert "not finite" in loop.on_pose(float("nan"), _pose(0.2, 0.0, 0.0))
    assert loop.refused["pose"] == 5 and loop.last_refusal.startswith("pose: ")
    assert loop.pose == pytest.approx((0.1, 0.0, 0.0))
    assert loop.tick(1.5).state == FOLLOWING


def test_a_frame_of_another_size_than_camera_info_is_refused():
    loop, cfg = _loop(True, goal_xy=(2.0, 0.0))
    assert loop.on_pose(0.0, _pose(0.0, 0.0, 0.0)) is None
    k = cfg.intrinsics
    why = loop.on_frame(0.0, np.zeros((100, 100), np.float32))
    assert why == f"size 100x100 differs from the camera's {k.width}x{k.height} (camera_info)"
    assert loop.on_frame(0.0, None) is not None and loop.refused["frame"] == 2
    assert loop.tick(0.1).state == WAITING                 # no frame was taken
    assert loop.on_frame(0.0, _frame(cfg)) is None
    assert "older than the last frame" in loop.on_frame(-1.0, _frame(cfg))
    assert loop.tick(0.1).state == FOLLOWING


def test_a_stale_frame_holds_until_a_fresh_one_then_replans_at_once():
    loop, cfg = _loop(True, goal_xy=(2.0, 0.0), frame_timeout_s=3.0)
    _feed(loop, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    assert not loop.tick(0.5).hold and loop.replans == 1
    for t in np.arange(0.5, 6.01, 0.5):                    # poses go on, the camera is silent
        loop.on_pose(float(t), _pose(0.0, 0.0, 0.0))
    out = loop.tick(6.0)
    assert out.state == STALE and out.hold and out.message == "camera frame 6.0 s old (frame_timeout_s 3): holding"
    assert loop.tick(6.0).hold and loop.replans == 1        # nothing planned on the old frame
    _feed(loop, cfg, 6.2, _pose(0.0, 0.0, 0.0))
    out = loop.tick(6.3)                                    # long before replan_period_s: at once
    assert out.state == FOLLOWING and not out.hold and out.replan is not None and loop.replans == 2


def test_a_stale_pose_or_a_stamp_ahead_of_the_clock_holds():
    loop, cfg = _loop(True, goal_xy=(2.0, 0.0), pose_timeout_s=1.0)
    _feed(loop, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    assert not loop.tick(0.2).hold
    loop.on_frame(2.0, _frame(cfg))
    out = loop.tick(2.0)
    assert out.state == STALE and out.hold and out.message.startswith("base pose 2.0 s old (pose_timeout_s 1)")
    _feed(loop, cfg, 5.0, _pose(0.0, 0.0, 0.0))
    out = loop.tick(2.1)                                    # the inputs' clock is 2.9 s ahead
    assert out.state == STALE and "ahead of the clock" in out.message


def test_an_exception_in_the_tick_holds_and_the_next_tick_works():
    cfg = dataclasses.replace(NavConfig.from_yaml(PERCEPTION_SPACE))
    cfg = dataclasses.replace(cfg, sampler=dataclasses.replace(cfg.sampler, min_free_m=0.5))
    k, calls = cfg.intrinsics, []

    def perception(image):
        calls.append(1)
        if len(calls) == 1:
            raise ValueError("a perception bug")
        return np.ones((k.height, k.width), bool)
    loop = NavLoop(cfg, 0.09, perception, goal_xy=(2.0, 0.0))
    _feed(loop, cfg, 0.0, _pose(0.0, 0.0, 0.0))
    out = loop.tick(0.1)
    assert out.state == ERROR and out.hold and "ValueError: a perception bug" in out.message
    assert loop.errors == 1 and loop.last_error == "ValueError: a perception bug"
    out = loop.tick(0.2)                                    # replanned at once, not a period later
    assert out.state == FOLLOWING and not out.hold and out.replan is not None


def test_bad_timeouts_and_goals_are_refused_with_their_values():
    with pytest.raises(ValueError, match="frame_timeout_s: must be a finite number > 0, got nan"):
        _loop(True, frame_timeout_s=float("nan"))
    with pytest.raises(ValueError, match="pose_timeout_s: .* got -1"):
        _loop(True, pose_timeout_s=-1)
    with pytest.raises(ValueError, match="goal_xy: must be finite"):
        _loop(True, goal_xy=(float("inf"), 0.0))
