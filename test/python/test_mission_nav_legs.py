"""Missions with navigate_to legs: the parser takes a valid leg and names every bad field with its value;
the runner hands a leg to its navigator, sends no gait command while it runs, goes on with the tracker
once the leg is reached, and aborts naming the leg when the navigator fails, the leg's time runs out or
there is no navigator; abort and pause cancel the leg's goal. The batch simulator refuses such missions."""
import math

import pytest

from snake_autonomy.missions import MissionError, validate_mission
from snake_autonomy.missions.nav_leg import ACTIVE, FAILED, PENDING, SUCCEEDED, NavLegSpec
from snake_autonomy.missions.runner import ABORTED, DONE, RUNNING, MissionRunner
from snake_autonomy.nodes.mission_action import fill_feedback

LEG = {"navigate_to": {"x_m": 2.0, "y_m": 0.5, "radius_m": 0.2, "time_limit_s": 30}}


def mission(*waypoints, **extra):
    return validate_mission({"name": "legs", "waypoints": list(waypoints), **extra}, "legs.yaml")


class FakeNavigator:
    def __init__(self):
        self.state, self.sent, self.cancels = (PENDING, "waiting"), [], 0

    def send(self, index, leg):
        self.sent.append((index, leg))

    def poll(self):
        return self.state

    def cancel(self):
        self.cancels += 1


def started(m, navigator):
    runner = MissionRunner(m, yaw_window=1, navigator=navigator)
    runner.start(0.0)
    return runner


def tick(runner, t, x=0.0, y=0.0, yaw=0.0):
    runner.on_pose(t, x, y, yaw)
    return runner.step(t)


def test_a_valid_leg_is_a_waypoint_with_its_leg():
    m = mission([0.5, 0.0, 0.0], LEG, {"navigate_to": {"x_m": -1, "y_m": 0, "heading_deg": 90}})
    assert m.legs == {1: NavLegSpec(2.0, 0.5, 0.0, 0.2, 30.0), 2: NavLegSpec(-1.0, 0.0, 90.0)}
    assert m.waypoints_deg == [(0.5, 0.0, 0.0), (2.0, 0.5, 0.0), (-1.0, 0.0, 90.0)]
    assert "1: navigate_to x +2.000 m  y +0.500 m" in m.summary()
    assert "0: track" in m.summary()


@pytest.mark.parametrize("entry,problem", [
    ({"navigate_to": {"x_m": 1.0}}, "waypoints[0].navigate_to.y_m: missing"),
    ({"navigate_to": {"x_m": "far", "y_m": 0}}, "waypoints[0].navigate_to.x_m: must be a number within +-1000 m, "
                                                "got 'far'"),
    ({"navigate_to": {"x_m": 1, "y_m": 0, "radius_m": 0}}, "waypoints[0].navigate_to.radius_m: must be a number "
                                                           "in (0, 100] m, got 0"),
    ({"navigate_to": {"x_m": 1, "y_m": 0, "time_limit_s": -5}}, "waypoints[0].navigate_to.time_limit_s: must be a "
                                                                "number in (0, 86400] s, got -5"),
    ({"navigate_to": {"x_m": 1, "y_m": 0, "heading_deg": math.inf}}, "waypoints[0].navigate_to.heading_deg: must "
                                                                      "be a number within +-360, got inf"),
    ({"navigate_to": {"x_m": 1, "y_m": 0, "radius": 0.2}}, "waypoints[0].navigate_to.radius: unknown key (value 0.2)"),
    ({"navigate_to": [1, 0]}, "waypoints[0].navigate_to: expected a mapping with keys x_m, y_m"),
    ({"navigate_to": {"x_m": 1, "y_m": 0}, "pose": [1, 0, 0]}, "waypoints[0].pose: give pose or navigate_to, "
                                                               "not both (pose [1, 0, 0])"),
])
def test_a_bad_leg_is_refused_naming_the_field_and_value(entry, problem):
    with pytest.raises(MissionError) as err:
        mission(entry)
    assert any(p.startswith(problem) for p in err.value.problems), err.value.problems
    assert len(err.value.problems) == 1, err.value.problems


def test_every_bad_leg_is_listed_at_once():
    with pytest.raises(MissionError) as err:
        mission({"navigate_to": {"x_m": None, "y_m": 0}}, [1, 0, 0], {"navigate_to": {"y_m": 0, "foo": 1}})
    assert [p.split(":")[0] for p in err.value.problems] == [
        "waypoints[0].navigate_to.x_m", "waypoints[2].navigate_to.foo", "waypoints[2].navigate_to.x_m"]


def test_a_leg_runs_on_the_navigator_then_the_tracker_goes_on():
    nav = FakeNavigator()
    runner = started(mission([1.0, 0.0, 0.0], LEG, [3.0, 0.5, 0.0]), nav)
    assert tick(runner, 0.1, 0.0).gait == "sidewind"
    assert tick(runner, 0.2, 0.9).status["waypoint_reached"]          # the tracker reached waypoint 0
    d = tick(runner, 0.3, 0.9)
    assert nav.sent == [(1, runner.mission.legs[1])]
    assert d.navigating and not d.finished and d.status["gait"] == "navigate_to"
    assert d.status["waypoint_index"] == 1 and d.leg_state == "waiting"
    nav.state = (ACTIVE, "move_base goal active")
    d = tick(runner, 0.4, 1.0)
    assert d.navigating and d.leg_state == "move_base goal active"
    assert d.status["distance"] == pytest.approx(math.hypot(1.0, 0.5))
    nav.state = (SUCCEEDED, "move_base goal succeeded")
    d = tick(runner, 0.5, 1.0)
    assert d.status["waypoint_reached"] and d.status["waypoint_index"] == 2 and not d.finished
    assert d.leg_state == "reached: move_base goal succeeded" and nav.cancels == 0
    fb = fill_feedback(type("Feedback", (), {})(), d.status, d.leg_state)
    assert (fb.leg, fb.waypoint_index) == ("navigate_to", 2)
    d = tick(runner, 0.6, 2.0, 0.5)
    assert not d.navigating and d.gait == "sidewind" and d.status["waypoint_index"] == 2
    assert fill_feedback(type("Feedback", (), {})(), d.status, d.leg_state).leg == "track"
    assert len(nav.sent) == 1


def test_a_last_leg_reached_ends_the_mission_done_with_a_hold():
    nav = FakeNavigator()
    runner = started(mission(LEG), nav)
    assert tick(runner, 0.1).navigating
    nav.state = (SUCCEEDED, "move_base goal succeeded")
    d = tick(runner, 0.2)
    assert d.finished and not d.navigating and d.gait == "hold" and runner.state == DONE


def test_a_failed_leg_aborts_the_mission_naming_the_leg_and_the_reason():
    nav = FakeNavigator()
    runner = started(mission(LEG, [3, 0, 0]), nav)
    tick(runner, 0.1)
    nav.state = (FAILED, "move_base goal aborted: no free arc")
    d = tick(runner, 0.2)
    assert d.finished and d.gait == "hold" and not d.navigating and runner.state == ABORTED
    assert runner.outcome == "aborted: waypoints[0] navigate_to (2, 0.5): move_base goal aborted: no free arc"
    assert nav.cancels == 0      # the server ended the goal itself


def test_a_leg_out_of_time_aborts_and_cancels_its_goal():
    nav = FakeNavigator()
    runner = started(mission({"navigate_to": {"x_m": 2, "y_m": 0, "time_limit_s": 5}}), nav)
    tick(runner, 1.0)
    assert tick(runner, 5.5).navigating
    d = tick(runner, 6.5)
    assert d.finished and runner.outcome == "aborted: waypoints[0] navigate_to (2, 0): time limit 5 s reached"
    assert nav.cancels == 1


def test_inside_the_radius_the_leg_is_reached_and_its_goal_cancelled():
    nav = FakeNavigator()
    runner = started(mission(LEG, [3, 0.5, 0]), nav)
    tick(runner, 0.1)
    nav.state = (ACTIVE, "move_base goal active")
    assert tick(runner, 0.2, 1.7, 0.5).navigating                   # 0.3 m away: radius_m is 0.2
    d = tick(runner, 0.3, 1.9, 0.5)
    assert d.status["waypoint_reached"] and nav.cancels == 1 and runner.state == RUNNING
    assert d.leg_state.startswith("reached: centre of mass 0.10 m from the goal (radius_m 0.2)")


def test_without_a_navigator_a_leg_aborts_the_mission():
    runner = started(mission(LEG), None)
    d = tick(runner, 0.1)
    assert d.finished and runner.state == ABORTED
    assert runner.outcome.startswith("aborted: waypoints[0] navigate_to (2, 0.5): no navigator")


def test_abort_cancels_the_leg_and_pause_sends_it_again_on_resume():
    nav = FakeNavigator()
    runner = started(mission(LEG), nav)
    tick(runner, 0.1)
    assert runner.pause("driver fault") and nav.cancels == 1
    d = tick(runner, 0.2)
    assert not d.navigating and d.gait == "hold"                     # the pause holds the robot itself
    assert runner.resume()
    assert tick(runner, 0.3).navigating and len(nav.sent) == 2
    runner.abort("operator request")
    assert nav.cancels == 2 and runner.state == ABORTED
    runner.close()
    assert nav.cancels == 2                                          # nothing left to cancel


def test_the_batch_simulator_refuses_a_mission_with_legs():
    from snake_autonomy.runs.batch import refuse_navigation_legs
    refuse_navigation_legs(mission([1, 0, 0]))                       # tracker waypoints only: fine
    with pytest.raises(MissionError) as err:
        refuse_navigation_legs(mission([1, 0, 0], LEG))
    assert err.value.problems == ["waypoints[1] navigate_to (2, 0.5): navigate_to legs need the planner: "
                                  "run through ROS (sim.launch world:=...)"]


def test_a_scout_stop_on_a_leg_comes_once_the_leg_is_reached():
    nav = FakeNavigator()
    runner = started(mission({**LEG, "scout": {"height_m": 0.3, "hold_s": 2}}, [3, 0.5, 0]), nav)
    assert set(runner.mission.scouts) == set(runner.mission.legs) == {0}
    tick(runner, 0.1)
    assert runner.scout_log == []
    nav.state = (SUCCEEDED, "move_base goal succeeded")
    tick(runner, 0.2)
    # no scout planner on this path: the stop is recorded as failed and the mission goes on
    assert [r.waypoint_index for r in runner.scout_log] == [0]
    assert runner.scout_log[0].outcome.startswith("failed: no scout planner")
    assert runner.state == RUNNING and runner.tracker.waypoint_index == 1
