"""The mission's TopicTrajectoryExecutor never waits forever for a scout trajectory: a final status in
time is success; no status at all within the acceptance timeout, or no final status within the
trajectory's duration + the margin, ends it as given up with a message naming the trajectory, the
wait and what was expected; a late final status of a trajectory given up, and a status of another id,
are ignored. A mission whose raise is given up ends aborted with the head held (no gait command).
No ROS master: a fake publisher, statuses handed to on_status, the caller's clock."""
import logging
from dataclasses import dataclass
from typing import List, Tuple

import pytest

from snake_autonomy.missions import validate_mission
from snake_autonomy.missions.runner import MissionRunner
from snake_autonomy.missions.scout import ScoutPlan
from snake_autonomy.msg import TrajectoryStatus
from snake_autonomy.nodes.scout_trajectory import TopicTrajectoryExecutor

WAIT_S = 10.0


class FakePublisher:
    resolved_name = "/driver/joint_trajectory"

    def __init__(self, connections=1):
        self.connections, self.sent = connections, []

    def get_num_connections(self):
        return self.connections

    def publish(self, msg):
        self.sent.append(msg)


@dataclass
class Point:
    time_from_start_s: float
    positions_rad: Tuple[float, ...] = (0.0, 0.0)
    velocities_rad_s: Tuple[float, ...] = (0.0, 0.0)


@dataclass
class Trajectory:
    points: List[Point]
    joint_names: Tuple[str, ...] = ("joint_1", "joint_2")


def trajectory(duration_s):
    return Trajectory([Point(duration_s / 2), Point(duration_s)])


def status(trajectory_id, phase, abort="", reason=""):
    return TrajectoryStatus(id=trajectory_id, phase=phase, abort=abort, reason=reason)


def executor(**kw):
    pub = FakePublisher()
    return TopicTrajectoryExecutor(publisher=pub, subscribe=False, accept_timeout_s=2.0, result_margin_s=5.0,
                                   **kw), pub


def test_a_final_status_in_time_is_success():
    ex, pub = executor()
    assert ex.execute(trajectory(7.0), 100.0) == ""
    goal = pub.sent[0].header.frame_id
    ex.on_status(status(goal, "running"))
    assert not ex.finished(106.0)
    ex.on_status(status(goal, "done"))
    assert ex.finished(107.1) and ex.aborted == ""


def test_no_final_status_ends_after_the_trajectory_and_the_margin_naming_the_wait():
    ex, pub = executor()
    ex.execute(trajectory(7.0), 100.0)
    goal = pub.sent[0].header.frame_id
    ex.on_status(status(goal, "running"))
    assert not ex.finished(111.9)                   # 7 s trajectory + 5 s margin from its sending
    assert ex.finished(112.1)
    assert ex.aborted == f"no final status for trajectory '{goal}' within 12.0 s (7.0 s trajectory + 5.0 s)"
    assert ex.finished(200.0)                       # stays ended: nothing is waited for any more


def test_a_driver_that_never_answers_ends_after_the_acceptance_timeout():
    ex, pub = executor()
    ex.execute(trajectory(30.0), 100.0)
    assert not ex.finished(101.9)
    assert ex.finished(102.1)
    goal = pub.sent[0].header.frame_id
    assert ex.aborted.startswith(f"no status for trajectory '{goal}' within 2.0 s of sending it")
    assert "driver/trajectory_status" in ex.aborted


def test_a_late_final_and_other_ids_are_ignored(caplog):
    ex, pub = executor()
    ex.execute(trajectory(1.0), 100.0)
    first = pub.sent[0].header.frame_id
    ex.on_status(status("someone else's", "done"))          # not ours: no effect
    ex.on_status(status(first, "running"))
    assert not ex.finished(105.9)
    assert ex.finished(106.1) and "no final status" in ex.aborted
    given_up = ex.aborted
    with caplog.at_level(logging.DEBUG):
        ex.on_status(status(first, "done"))                  # late: after it was given up
    assert ex.finished(106.2) and ex.aborted == given_up
    assert any("came after it was given up" in r.getMessage() for r in caplog.records)
    # the next trajectory is followed on its own; the late final of the first does not end it
    ex.execute(trajectory(1.0), 110.0)
    second = pub.sent[1].header.frame_id
    assert second != first and ex.aborted == ""
    ex.on_status(status(first, "done"))
    ex.on_status(status(second, "running"))
    assert not ex.finished(110.5)
    ex.on_status(status(second, "aborted", "hold_request", "driver/hold called"))
    assert ex.finished(110.6) and ex.aborted == "aborted hold_request: driver/hold called"


@pytest.mark.parametrize("key,value", [("accept_timeout_s", 0.0), ("result_margin_s", float("nan"))])
def test_deadlines_must_be_positive(key, value):
    with pytest.raises(ValueError, match=f"~scout_{key}: must be a positive number of seconds"):
        TopicTrajectoryExecutor(publisher=FakePublisher(), subscribe=False, **{key: value})


def test_a_raise_given_up_aborts_the_mission_holding_the_head():
    m = validate_mission({"name": "s", "waypoints": [{"pose": [1.0, 0.0, 0.0], "scout": {"hold_s": 1}},
                                                     [3.0, 0.0, 0.0]]}, "s")
    ex, pub = executor()
    r = MissionRunner(m, pose_timeout_s=1e6, yaw_window=1, executor=ex,
                      scout_planner=lambda spec: ScoutPlan(trajectory(7.0), trajectory(7.0)))
    r.start(0.0)
    r.on_pose(0.0, 1.0, 0.0, 0.0)
    r.step(1.0)
    assert r.scout.wait_planned(WAIT_S)
    d = r.step(2.0)                                          # the raise is out by now
    assert d.trajectory_active and len(pub.sent) == 1
    ex.on_status(status(pub.sent[0].header.frame_id, "running"))   # then the driver goes silent
    t = 3.0
    while r.state == "running" and t < 60.0:
        d = r.step(t)
        t += 1.0
    goal = pub.sent[0].header.frame_id
    sent_s = r.scout_log[0].phases["raising"]
    assert sent_s + 12.0 < d.t_s <= sent_s + 13.0           # the first 1 Hz tick past 7 + 5 s
    assert r.state == "aborted" and d.finished and d.trajectory_active and d.hold
    assert r.outcome == (f"aborted: scout at waypoint 0: failed: raising: no final status for trajectory "
                         f"'{goal}' within 12.0 s (7.0 s trajectory + 5.0 s)")
    assert len(pub.sent) == 1                                # no lowering sent to a driver that is not there
    r.close()
