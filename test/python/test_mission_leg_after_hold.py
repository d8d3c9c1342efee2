"""A navigate_to leg's after-hold in MissionRunner: once a leg is reached, through its move_base goal or
inside its radius_m, the runner sends the hold gait every tick for leg_hold_s (the navigator's settle_s),
then the tracker's gait at the very next tick: the driver hears a command at every tick from the planner's
last one on (mission_node sends a decision's gait unless it is navigating or a trajectory owns the joints)."""
from snake_autonomy.missions.nav_leg import ACTIVE, SUCCEEDED
from snake_autonomy.missions.runner import RUNNING, MissionRunner

from test_mission_nav_legs import LEG, FakeNavigator, mission

SETTLE_S = 3.0


class SettlingNavigator(FakeNavigator):
    settle_s = SETTLE_S       # as MoveBaseNavigator's ~nav_settle_s


def runner_on(m, nav):
    runner = MissionRunner(m, yaw_window=10, navigator=nav)
    runner.start(0.0)
    return runner


def second(runner, t, x, y):
    """One 1 Hz control tick after a second of poses at 20 Hz (the yaw filter refills after a reset)."""
    for k in range(20):
        runner.on_pose(t - 1.0 + (k + 1) / 20.0, x, y, 0.0)
    return runner.step(t)


def sends_gait(d):
    """Whether mission_node publishes a gait command for this decision."""
    return not (d.navigating or d.trajectory_active)


def drive_leg_then_end(runner, nav, end):
    """Ticks at 1 s: the leg's goal sent and active (the planner commands), end(t) at t = 4 s, then ticks
    until 9 s; the decisions from the leg's end on."""
    assert second(runner, 1.0, 0.0, 0.0).navigating
    nav.state = (ACTIVE, "move_base goal active")
    for t in (2.0, 3.0):
        assert second(runner, t, 0.5, 0.2).navigating
    return [end(t) for t in (4.0, 5.0, 6.0, 7.0, 8.0)]


def assert_hold_then_tracker(runner, after):
    gaits = [d.gait for d in after]
    assert all(sends_gait(d) for d in after), [(d.t_s, d.navigating) for d in after]
    hold = runner.hold_gait
    assert gaits[:3] == [hold] * 3                   # 4, 5 and 6 s: the after-hold, SETTLE_S long
    assert after[0].status["waypoint_reached"] and after[0].leg_state.startswith("reached: ")
    assert "holding 3.0 s before going on" in after[0].status["note"]
    assert all(d.hold and not d.finished for d in after[:3])
    assert hold not in gaits[3:] and not after[3].status["pose_stale"]   # 7 s: the tracker's gait
    assert after[3].leg_state == "" and after[3].status["waypoint_index"] == 1
    assert runner.state == RUNNING


def test_the_after_hold_length_is_the_navigators_settle():
    assert runner_on(mission(LEG, [3, 0.5, 0]), SettlingNavigator()).leg_hold_s == SETTLE_S
    assert runner_on(mission(LEG, [3, 0.5, 0]), FakeNavigator()).leg_hold_s == 0.0
    assert MissionRunner(mission(LEG), navigator=SettlingNavigator(), leg_hold_s=1.5).leg_hold_s == 1.5


def test_a_succeeded_goal_is_followed_by_the_hold_then_the_tracker_with_no_silent_tick():
    nav = SettlingNavigator()
    runner = runner_on(mission(LEG, [3, 0.5, 0]), nav)

    def end(t):
        nav.state = (SUCCEEDED, "move_base goal succeeded")
        return second(runner, t, 1.0, 0.5)                 # 1 m from the goal: radius_m plays no part
    after = drive_leg_then_end(runner, nav, end)
    assert_hold_then_tracker(runner, after)
    assert after[0].leg_state.startswith("reached: move_base goal succeeded") and nav.cancels == 0


def test_a_leg_ended_by_its_radius_gets_the_same_after_hold():
    nav = SettlingNavigator()
    runner = runner_on(mission(LEG, [3, 0.5, 0]), nav)
    after = drive_leg_then_end(runner, nav, lambda t: second(runner, t, 1.9, 0.5))   # 0.1 m from the goal
    assert nav.cancels == 1 and nav.state[0] == ACTIVE    # the goal cancelled, not succeeded
    assert_hold_then_tracker(runner, after)
    assert after[0].leg_state.startswith("reached: centre of mass 0.10 m from the goal (radius_m 0.2)")


def test_a_scout_stop_on_a_leg_starts_after_the_after_hold():
    nav = SettlingNavigator()
    runner = runner_on(mission({**LEG, "scout": {"height_m": 0.3, "hold_s": 2}}, [3, 0.5, 0]), nav)
    second(runner, 1.0, 0.0, 0.0)
    nav.state = (SUCCEEDED, "move_base goal succeeded")
    for t in (2.0, 3.0, 4.0):
        assert sends_gait(second(runner, t, 1.0, 0.5)) and runner.scout_log == []
    second(runner, 5.0, 1.0, 0.5)
    # no scout planner on this path: the stop is recorded as failed once the hold is over
    assert [r.waypoint_index for r in runner.scout_log] == [0]
