"""planner_node's ROS-free logic (planning/rectilinear/nav_loop.py): replans from the latest frame
and pose, hold while waiting, with no free arc and at the goal; the image message conversions."""
import dataclasses
import math

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear.config import NavConfig
from snake_autonomy.planning.rectilinear.nav_loop import (FOLLOWING, GOAL_REACHED, NO_FREE_ARC, WAITING,
                                                          NavLoop)


def _pose(x, y, th, z=0.045):
    T = np.eye(4)
    T[:2, :2] = [[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]
    T[:3, 3] = (x, y, z)
    return T


def _loop(ground_value, **kw):
    cfg = NavConfig.from_yaml()
    # the footprint's near field (hidden under the view) counts as free: ask for more than it
    cfg = dataclasses.replace(cfg, sampler=dataclasses.replace(cfg.sampler, min_free_m=0.5))
    k = cfg.intrinsics
    return NavLoop(cfg, 0.09, lambda img: np.full((k.height, k.width), ground_value, bool), **kw), cfg


def test_open_floor_follows_and_replans_on_the_period():
    loop, cfg = _loop(True, goal_xy=(2.0, 0.0), goal_radius_m=0.1)
    assert loop.tick(0.0).state == WAITING and loop.tick(0.0).hold
    loop.on_pose(0.0, _pose(0.0, 0.0, 0.0))
    loop.on_frame(0.0, np.zeros((1, 1)))
    out = loop.tick(0.5)
    assert out.state == FOLLOWING and not out.hold and out.replan is not None
    assert out.replan.path_world is not None and out.replan.path_world[-1, 0] > 0.5
    assert abs(out.kappa_per_m) < 0.1                    # straight ahead to the goal
    assert loop.tick(1.0).replan is None                  # next replan after replan_period_s
    assert loop.tick(0.5 + cfg.replan_period_s).replan is not None
    assert loop.replans == 2


def test_no_free_arc_holds_or_turns():
    loop, _ = _loop(False, goal_xy=(2.0, 0.0))
    loop.on_pose(0.0, _pose(0.0, 0.0, 0.0))
    loop.on_frame(0.0, None)
    out = loop.tick(0.0)
    assert out.state == NO_FREE_ARC and out.hold and out.replan.path_world is None
    assert "no collision-free arc" in out.message and loop.stops_no_free_arc == 1
    turn, _ = _loop(False, goal_xy=(2.0, 0.0), on_no_free_arc="turn")
    turn.on_pose(0.0, _pose(0.0, 0.0, 0.0))
    turn.on_frame(0.0, None)
    turn.tick(0.0)
    out = turn.tick(30.0)                               # kappa rate-limited towards kappa_turn_per_m
    assert not out.hold and out.kappa_per_m != 0.0 and not out.backwards
    back, _ = _loop(False, goal_xy=(2.0, 0.0), on_no_free_arc="back_off")
    back.on_pose(0.0, _pose(0.0, 0.0, 0.0))
    back.on_frame(0.0, None)
    out = back.tick(0.0)
    assert out.state == NO_FREE_ARC and "backing off" in out.message
    out = back.tick(5.0)
    assert not out.hold and out.backwards and out.kappa_per_m == 0.0      # the reverse gait, kappa held


def test_goal_reached_holds_for_good():
    loop, _ = _loop(True, goal_xy=(1.0, 0.0), goal_radius_m=0.2)
    loop.on_frame(0.0, None)
    loop.on_pose(0.0, _pose(0.9, 0.05, 0.3))
    out = loop.tick(1.0)
    assert out.state == GOAL_REACHED and out.hold
    loop.on_pose(2.0, _pose(0.0, 0.0, 0.0))
    assert loop.tick(2.0).state == GOAL_REACHED


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="on_no_free_arc"):
        _loop(True, on_no_free_arc="spin")
    with pytest.raises(ValueError, match="goal_radius_m"):
        _loop(True, goal_radius_m=0.0)


def test_image_messages_round_trip():
    pytest.importorskip("sensor_msgs.msg")
    from snake_autonomy.nodes.image_msgs import from_camera_info, from_image, to_camera_info, to_image
    from snake_autonomy.sim.camera import CameraIntrinsics
    rgb = np.random.default_rng(0).integers(0, 255, (4, 5, 3), dtype=np.uint8)
    assert np.array_equal(from_image(to_image(rgb, "rgb8", None, "cam")), rgb)
    assert np.array_equal(from_image(to_image(rgb[..., ::-1], "bgr8", None, "cam")), rgb)
    depth = np.linspace(0, 3, 20, dtype=np.float32).reshape(4, 5)
    assert np.array_equal(from_image(to_image(depth, "32FC1", None, "cam")), depth)
    mm = from_image(to_image((depth * 1000).astype(np.uint16), "16UC1", None, "cam"))
    assert mm == pytest.approx(depth, abs=1e-3)
    k = CameraIntrinsics(640, 480, 615.0, 610.0, 320.0, 240.0)
    assert from_camera_info(to_camera_info(k, None, "cam")) == k


def test_a_replan_uses_the_pose_at_the_frames_stamp():
    loop, _ = _loop(True, goal_xy=(2.0, 0.0))
    for k in range(11):
        loop.on_pose(0.1 * k, _pose(0.01 * k, 0.0, 0.0))
    loop.on_frame(0.42, None)
    out = loop.tick(1.0)
    assert out.replan.pose[0] == pytest.approx(0.04)       # the pose of t 0.4, not the latest (0.10)
    assert loop.pose[0] == pytest.approx(0.10)
