"""The mission action `scout`: the schema (every problem listed) and the sequence in MissionRunner with a
fake planner and executor: plan off the loop -> raise -> hold -> lower -> resume; a failed plan is
never sent and the mission resumes."""
import json
import math
import threading

import pytest

from snake_autonomy.missions import MissionError, validate_mission
from snake_autonomy.missions.runner import MissionRunner
from snake_autonomy.missions.scout import ScoutPlan, ScoutSpec

WAIT_S = 10.0


def mission(scout=None, pose=(1.0, 0.0, 0.0)):
    first = {"pose": list(pose)}
    if scout is not None:
        first["scout"] = scout
    return validate_mission({"name": "s", "waypoints": [first, [3.0, 0.0, 0.0]]}, "s")


def test_scout_waypoint_is_parsed():
    m = mission({"height_m": 0.3, "hold_s": 5, "max_active": 6})
    assert m.waypoints[0] == (1.0, 0.0, 0.0) and m.scouts == {0: ScoutSpec(0.3, 5.0, 6, 0)}
    assert "then scout: head 0.3 m, hold 5 s" in m.summary()
    assert mission().scouts == {}


def test_bad_scout_entries_are_refused_with_every_problem():
    data = {"waypoints": [
        {"pose": [1.0, 0.0, 0.0], "scout": {"height_m": -0.3, "hold_s": "long", "max_active": 0,
                                              "seed": 1.5, "speed": 3}},
        {"scout": {"hold_s": 1}},
        {"pose": [2.0, 0.0, 0.0], "scout": [0.3], "when": "now"}]}
    with pytest.raises(MissionError) as err:
        validate_mission(data, "bad")
    problems = err.value.problems
    for text in ("waypoints[0].scout.height_m: must be a number in (0, 5] m, got -0.3",
                 "waypoints[0].scout.hold_s: must be a number in [0, 3600] s, got 'long'",
                 "waypoints[0].scout.max_active: must be an integer >= 1, got 0",
                 "waypoints[0].scout.seed: must be an integer >= 0, got 1.5",
                 "waypoints[0].scout.speed: unknown key (value 3)",
                 "waypoints[1].pose: missing",
                 "waypoints[2].scout: expected a mapping",
                 "waypoints[2].when: unknown key"):
        assert any(text in p for p in problems), (text, problems)


class FakeTrajectory:
    def __init__(self, name, duration_s):
        self.name, self.duration_s = name, duration_s


class FakeExecutor:
    def __init__(self, refuse=(), abort=()):
        self.sent, self.refuse, self.abort, self._end = [], set(refuse), set(abort), -math.inf
        self.heights = []                   # what head_height_m returns, call after call (then NaN)
        self.aborted = ""

    def execute(self, trajectory, t_s):
        if trajectory.name in self.refuse:
            return "driver says no"
        self.sent.append((t_s, trajectory.name))
        self._end = t_s + trajectory.duration_s
        return ""

    def finished(self, t_s):
        if t_s < self._end:
            return False
        if self.sent and self.sent[-1][1] in self.abort:
            self.aborted = "aborted fault: servo 3 overload"
        return True

    def head_height_m(self):
        return self.heights.pop(0) if self.heights else math.nan


def planner(fail=None, gate=None):
    def plan(spec):
        if gate is not None:
            assert gate.wait(WAIT_S)
        if fail:
            raise ValueError(fail)
        return ScoutPlan(FakeTrajectory("raise", 4.0), FakeTrajectory("lower", 3.0), 0.3, 1.0, 6)
    return plan


def arrive(m, plan, executor):
    """A runner that has just reached waypoint 0 (pose on it, heading aligned)."""
    r = MissionRunner(m, pose_timeout_s=1e6, yaw_window=1, scout_planner=plan, executor=executor)
    r.start(0.0)
    r.on_pose(0.0, 1.0, 0.0, 0.0)
    return r


def test_scout_sequence_plans_off_the_loop_then_raises_holds_lowers_and_resumes():
    gate = threading.Event()
    ex = FakeExecutor()
    r = arrive(mission({"height_m": 0.3, "hold_s": 5}), planner(gate=gate), ex)
    d = r.step(1.0)                       # reached: planning starts in the worker, the loop goes on
    assert d.hold and d.gait == "hold" and not d.trajectory_active and "planning" in d.status["note"]
    d = r.step(2.0)                       # still planning: the tick is not blocked
    assert "planning" in d.status["note"] and ex.sent == []
    gate.set()
    assert r.scout.wait_planned(WAIT_S)
    d = r.step(3.0)
    assert d.trajectory_active and "raising" in d.status["note"] and ex.sent == [(3.0, "raise")]
    assert r.step(6.0).trajectory_active                     # raise runs until 7.0
    d = r.step(7.0)
    assert d.trajectory_active and "holding" in d.status["note"]
    assert "holding" in r.step(11.0).status["note"] and ex.sent == [(3.0, "raise")]
    d = r.step(12.0)                                         # hold_s 5 after 7.0: lower
    assert "lowering" in d.status["note"] and ex.sent[-1] == (12.0, "lower")
    assert r.step(14.0).trajectory_active
    r.on_pose(15.0, 1.0, 0.0, 0.0)
    d = r.step(15.0)                                         # lowered: locomotion resumes
    assert not d.trajectory_active and not d.hold and d.gait == "sidewind"
    assert d.status["waypoint_index"] == 1
    rec = r.scout_log[0].as_dict()
    assert rec["outcome"] == "done" and rec["planned_head_height_m"] == 0.3
    assert rec["measured_head_height_m"] is None                 # not measured on this path: JSON null
    json.dumps(rec, allow_nan=False)                             # what metrics.json needs
    assert list(rec["phases"]) == ["planning", "raising", "holding", "lowering", "done"]
    r.close()


@pytest.mark.parametrize("plan,refuse,why", [
    (planner(fail="ZMP leaves the polygon"), (), "failed: plan: ZMP leaves the polygon"),
    (planner(), ("raise",), "failed: raising: the executor refused the trajectory (driver says no)")])
def test_a_plan_that_fails_is_never_sent_and_the_mission_resumes(plan, refuse, why):
    ex = FakeExecutor(refuse)
    r = arrive(mission({"hold_s": 1}), plan, ex)
    r.step(1.0)
    assert r.scout.wait_planned(WAIT_S)
    r.on_pose(2.0, 1.0, 0.0, 0.0)
    d = r.step(2.0)
    assert ex.sent == [] and not d.trajectory_active and not d.hold and d.gait == "sidewind"
    assert r.scout is None and r.scout_log[0].outcome == why
    r.close()


def test_without_a_planner_or_executor_the_stop_is_recorded_and_skipped():
    r = arrive(mission({"hold_s": 1}), None, None)
    d = r.step(1.0)
    assert not d.hold and "no scout planner" in r.scout_log[0].outcome


def test_scout_at_the_last_waypoint_finishes_the_mission_after_lowering():
    m = validate_mission({"waypoints": [{"pose": [1.0, 0.0, 0.0], "scout": {"hold_s": 0}}]}, "last")
    ex = FakeExecutor()
    r = arrive(m, planner(), ex)
    assert not r.step(1.0).finished
    assert r.scout.wait_planned(WAIT_S)
    t, d = 2.0, None
    while t < 30.0:
        d = r.step(t)
        if d.finished:
            break
        t += 1.0
    # the mission ends only once the head is down: at the tick the lowering (3 s) has finished
    assert d.finished and r.state == "done"
    assert [n for _, n in ex.sent] == ["raise", "lower"] and r.scout_log[0].outcome == "done"
    assert t == ex.sent[1][0] + 3.0 and ex.sent[1][0] >= ex.sent[0][0] + 4.0


def test_the_measured_head_height_is_the_lowest_the_executor_reads_while_held():
    m = validate_mission({"waypoints": [{"pose": [1.0, 0.0, 0.0], "scout": {"hold_s": 3}}]}, "held")
    ex = FakeExecutor()
    r = arrive(m, planner(), ex)
    r.step(1.0)
    assert r.scout.wait_planned(WAIT_S)
    t = 2.0
    while r.scout.phase != "holding":
        r.step(t)
        t += 1.0
    ex.heights = [0.31, math.nan, 0.29]            # one per tick while held; a NaN (no pose) is skipped
    while r.scout.phase == "holding":
        r.step(t)
        t += 1.0
    assert ex.heights == []                         # all three read: held 3 s, polled every second
    ex.heights = [0.05]                             # read after the hold: not the held height
    while not r.step(t).finished:
        t += 1.0
    rec = r.scout_log[0].as_dict()
    assert rec["outcome"] == "done" and rec["measured_head_height_m"] == pytest.approx(0.29)


def run_until_ended(ex):
    """A scout stop with hold_s 0 at waypoint 0, ticked at 1 Hz until the mission ends; (runner, last decision)."""
    r = arrive(mission({"hold_s": 0}), planner(), ex)
    r.step(1.0)
    assert r.scout.wait_planned(WAIT_S)
    t, d = 2.0, None
    while r.state == "running" and t < 30.0:
        d = r.step(t)
        t += 1.0
    return r, d


def test_a_refused_lowering_aborts_the_mission_with_the_head_held_up():
    ex = FakeExecutor(("lower",))
    r, d = run_until_ended(ex)
    assert r.state == "aborted" and "lowering: the executor refused" in r.outcome
    assert d.finished and d.trajectory_active and [n for _, n in ex.sent] == ["raise"]


@pytest.mark.parametrize("aborted", ["raise", "lower"])
def test_a_trajectory_that_ends_aborted_aborts_the_mission_with_the_head_held(aborted):
    ex = FakeExecutor(abort=(aborted,))
    r, d = run_until_ended(ex)
    phase = "raising" if aborted == "raise" else "lowering"
    assert r.outcome == f"aborted: scout at waypoint 0: failed: {phase}: aborted fault: servo 3 overload"
    assert d.finished and d.trajectory_active and ex.sent[-1][1] == aborted     # nothing sent after it


class DoneNavigator:
    """A navigator whose goal has succeeded as soon as it is sent."""
    settle_s = 0.0

    def __init__(self):
        self.sent = []

    def send(self, index, leg):
        self.sent.append(index)

    def poll(self):
        return ("succeeded", "move_base goal succeeded") if self.sent else ("pending", "")

    def cancel(self):
        pass


def test_scout_on_a_last_navigate_to_leg_raises_there_then_finishes_the_mission():
    m = validate_mission({"waypoints": [[0.5, 0.0, 0.0], {"navigate_to": {"x_m": 1.0, "y_m": 0.0},
                                                          "scout": {"height_m": 0.3, "hold_s": 2}}]}, "leg")
    ex, nav = FakeExecutor(), DoneNavigator()
    r = MissionRunner(m, pose_timeout_s=1e6, yaw_window=1, scout_planner=planner(), executor=ex, navigator=nav)
    r.start(0.0)
    r.on_pose(0.0, 0.5, 0.0, 0.0)
    r.step(0.5)                               # the tracker reaches waypoint 0: the leg is next
    d = r.step(1.0)                           # the leg's goal is sent and has succeeded
    assert nav.sent == [1] and d.status["waypoint_reached"] and not d.finished and r.scout is not None
    assert r.scout.wait_planned(WAIT_S)
    t, decisions = 2.0, []
    while r.state == "running" and t < 30.0:
        decisions.append(r.step(t))
        t += 1.0
    # raise 4 s, hold 2 s, lower 3 s: done at the tick the lowering has finished, never a gait before
    assert r.state == "done" and decisions[-1].finished and r.outcome == "done: every waypoint reached"
    assert [n for _, n in ex.sent] == ["raise", "lower"] and r.scout_log[0].outcome == "done"
    assert r.scout_log[0].waypoint_index == 1 and decisions[-1].t_s == ex.sent[1][0] + 3.0
    assert all(x.hold and x.gait == "hold" for x in decisions)
