"""The RunMission action's message side (nodes/mission_action.py), without ROS: which mission a goal
asks for, and the per-waypoint result built from the decisions of a run."""
import math
from types import SimpleNamespace

import pytest

from snake_autonomy.missions import MissionError
from snake_autonomy.nodes.mission_action import DecisionSeries, fill_feedback, fill_result, mission_from_goal

NAN = float("nan")


def goal(mission="", mission_yaml="", waypoints=(), name=""):
    return SimpleNamespace(mission=mission, mission_yaml=mission_yaml, waypoints=list(waypoints), name=name)


def pose2d(x, y, theta):
    return SimpleNamespace(x=x, y=y, theta=theta)


def test_a_goal_names_a_provided_mission_a_yaml_text_or_inline_waypoints():
    assert mission_from_goal(goal(mission="star"), None, None).name == "star"
    m = mission_from_goal(goal(mission_yaml="name: y\nwaypoints: [[1, 2, 90]]\ntime_limit_s: 30\n"), None, None)
    assert (m.name, m.waypoints_deg, m.time_limit_s) == ("y", [(1.0, 2.0, 90.0)], 30.0)
    m = mission_from_goal(goal(waypoints=[pose2d(1.0, 0.0, math.pi / 2), pose2d(2.0, 1.0, 0.0)], name="inl"),
                          None, None)
    assert m.name == "inl"
    assert m.waypoints_deg == [(1.0, 0.0, pytest.approx(90.0)), (2.0, 1.0, 0.0)]
    assert mission_from_goal(goal(waypoints=[pose2d(1.0, 0.0, 0.0)]), None, None).name == "inline"


@pytest.mark.parametrize("g, text", [
    (goal(), "got none"),
    (goal(mission="star", waypoints=[pose2d(1, 0, 0)]), "got mission, waypoints"),
    (goal(mission_yaml="waypoints: [[1, 2"), "not YAML"),
    (goal(mission_yaml="waypoints: []"), "the list is empty"),
    (goal(waypoints=[pose2d(NAN, 0, 0)]), "waypoints[0]"),
    (goal(mission="no_such_mission"), "file not found"),
])
def test_a_bad_goal_is_refused_naming_the_field(g, text):
    with pytest.raises(MissionError) as err:
        mission_from_goal(g, None, None)
    assert text in str(err.value)


def status(index, reached, distance, yaw=0.1, stale=False, n=2, gait="sidewind"):
    return dict(waypoint_index=index, num_waypoints=n, waypoint_reached=reached, distance=distance,
                yaw_error_abs=yaw, yaw_error_rel=yaw, yaw_error=yaw, mode=1, gait=gait, pose_stale=stale)


def test_the_result_carries_per_waypoint_metrics_and_the_feedback_a_decision():
    series = DecisionSeries()
    for t, st in ((10.0, status(0, False, 1.0)), (11.0, status(1, True, 0.3)), (12.0, status(1, False, NAN, stale=True)),
                  (13.0, status(1, False, 0.8)), (14.0, status(1, False, 0.6))):
        series.add(t, st)
    metrics = series.metrics([(1.0, 0.0, 0.0), (2.0, 0.0, math.pi / 2)], "aborted: test", t0=10.0)
    result = fill_result(SimpleNamespace(), SimpleNamespace, "m", "aborted", "aborted: test", metrics, path_length_m=0.9,
                         run_dir="/r")
    assert (result.mission, result.state, result.waypoints_reached, result.run_dir) == ("m", "aborted", 1, "/r")
    assert result.duration_s == pytest.approx(4.0)
    first, second = result.waypoints
    assert first.reached and first.time_to_reach_s == pytest.approx(1.0) and first.final_distance_m == pytest.approx(0.3)
    assert not second.reached and math.isnan(second.time_to_reach_s)
    assert second.final_distance_m == pytest.approx(0.6) and second.min_distance_m == pytest.approx(0.6)
    assert second.heading_deg == pytest.approx(90.0)
    fb = fill_feedback(SimpleNamespace(), status(1, False, NAN, stale=True, gait="hold"))
    assert (fb.waypoint_index, fb.num_waypoints, fb.gait, fb.pose_stale) == (1, 2, "hold", True)
    assert math.isnan(fb.distance)
