"""The mission runner: stale/lost poses hold the robot (ERRATA #7), end, abort, time limit."""
import math

import pytest

from snake_autonomy.missions import validate_mission
from snake_autonomy.missions.runner import MissionRunner


def runner(time_limit=None, waypoints=((1.0, 0.0, 0.0), (2.0, 0.0, 0.0))):
    data = {"name": "t", "waypoints": [list(w) for w in waypoints]}
    if time_limit:
        data["time_limit_s"] = time_limit
    return MissionRunner(validate_mission(data, "t"), pose_timeout_s=0.5, yaw_window=10)


def feed(r, t0, t1, x, y, yaw, rate=50.0):
    n = int(round((t1 - t0) * rate))
    for i in range(n):
        r.on_pose(t0 + i / rate, x, y, yaw)


def test_not_running_means_no_decision():
    r = runner()
    feed(r, 0, 1, 0, 0, 0)
    assert r.step(1.0) is None


def test_fresh_pose_drives_the_tracker_and_maps_gaits():
    r = runner()
    r.start(0.0)
    feed(r, 0.0, 1.0, -1.0, 0.0, 0.0)
    d = r.step(1.0)
    assert not d.hold and d.gait == "sidewind" and d.steer
    assert d.delta_rad == pytest.approx(math.radians(14.0))
    assert d.status["distance"] == pytest.approx(2.0) and d.status["pose_stale"] is False


def test_no_pose_yet_holds():
    r = runner()
    r.start(0.0)
    d = r.step(1.0)
    assert (d.hold, d.gait, d.steer, d.status["pose_stale"]) == (True, "hold", False, True)
    assert math.isnan(d.status["distance"]) and "no pose yet" in d.status["note"]


def test_stale_pose_holds_then_resumes_when_fresh():
    r = runner()
    r.start(0.0)
    feed(r, 0.0, 1.0, -1.0, 0.0, 0.0)
    assert not r.step(1.0).hold
    d = r.step(2.0)                       # last pose at ~0.98 s: 1.02 s old
    assert d.hold and d.status["pose_stale"] and "s old (timeout 0.5 s)" in d.status["note"]
    r.on_pose(2.5, -1.0, 0.0, 0.0)        # one pose is not enough: the yaw filter refills first
    d = r.step(2.55)
    assert d.hold and "waiting for fresh poses (1/10" in d.status["note"]
    feed(r, 2.6, 3.0, -1.0, 0.0, 0.0)
    d = r.step(3.0)
    assert not d.hold and d.gait == "sidewind"


@pytest.mark.parametrize("pose", [(float("nan"), 0.0, 0.0), (0.0, 0.0, float("inf"))])
def test_non_finite_pose_holds(pose):
    r = runner()
    r.start(0.0)
    feed(r, 0.0, 1.0, -1.0, 0.0, 0.0)
    assert r.on_pose(1.0, *pose) is False
    d = r.step(1.01)
    assert d.hold and "non-finite CoM pose" in d.status["note"]


def test_pose_source_lost_holds():
    r = runner()
    r.start(0.0)
    feed(r, 0.0, 1.0, -1.0, 0.0, 0.0)
    r.set_source_status(False, "odometry lost: covariance 9999")
    feed(r, 1.0, 2.0, -1.0, 0.0, 0.0)     # the driver may keep publishing a CoM from a stale base pose
    d = r.step(2.0)
    assert d.hold and "pose source: odometry lost" in d.status["note"]
    r.set_source_status(True, "tracking")
    feed(r, 2.0, 2.5, -1.0, 0.0, 0.0)
    assert not r.step(2.5).hold


def test_mission_done_holds():
    r = runner(waypoints=[(0.0, 0.0, 0.0)])
    r.start(0.0)
    feed(r, 0.0, 1.0, 0.1, 0.0, 0.0)
    d = r.step(1.0)
    assert (d.finished, d.hold, d.gait, r.state) == (True, True, "hold", "done")
    assert d.status["done"] and d.status["waypoint_reached"]
    assert r.step(2.0) is None


def test_time_limit():
    r = runner(time_limit=5)
    r.start(0.0)
    feed(r, 0.0, 6.0, -1.0, 0.0, 0.0)
    assert not r.step(5.0).hold
    d = r.step(5.5)
    assert (d.finished, d.hold, r.state) == (True, True, "timeout") and "time limit 5 s" in d.outcome


def test_abort():
    r = runner()
    r.start(0.0)
    r.abort("operator")
    assert r.state == "aborted" and r.step(1.0) is None
    d = r.final_decision(1.0)
    assert (d.hold, d.gait, d.outcome) == (True, "hold", "aborted: operator")
    with pytest.raises(RuntimeError, match="is aborted"):
        r.start(2.0)


def test_a_pause_holds_through_fresh_poses_until_resume():
    r = runner()
    r.start(0.0)
    feed(r, 0.0, 1.0, -1.0, 0.0, 0.0)
    assert not r.step(1.0).hold
    assert r.pause("driver fault: bus closed") and not r.pause("again")
    feed(r, 1.0, 3.0, -1.0, 0.0, 0.0)      # the driver recovered: poses flow, the mission still holds
    d = r.step(3.0)
    assert d.hold and d.gait == "hold" and not d.finished and r.running
    assert d.status["note"] == "paused: driver fault: bus closed (resume to go on)"
    assert r.resume() and not r.resume()
    assert r.step(3.0).hold                 # tracking restarts on poses after the resume
    feed(r, 3.0, 4.0, -1.0, 0.0, 0.0)
    d = r.step(4.0)
    assert not d.hold and d.gait == "sidewind" and d.status["waypoint_index"] == 0
    r.abort("operator")
    assert not r.pause("late") and not r.resume()
