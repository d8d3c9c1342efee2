"""Run logging: the results folder from plain arrays, and runs that end badly (SIGKILL, SIGTERM)."""
import json
import math
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from snake_autonomy.cli import main as cli_main
from snake_autonomy.runs.bag_io import read_run
from snake_autonomy.runs.results import compute_metrics, path_length, write_results
from snake_autonomy.runs.run_log import RunLog

HERE = Path(__file__).resolve().parent
WPS = [(1.0, 0.0, 0.0), (1.0, 1.0, math.pi / 2)]


def fake_decisions():
    # waypoint 0 reached at t = 12 (index 0 -> 1), waypoint 1 never; one stale step with NaN errors
    t = np.arange(10.0, 20.0)
    idx = np.array([0, 0, 1, 1, 1, 1, 1, 1, 1, 1])
    dist = np.array([1.0, 0.5, 0.3, 1.2, 1.0, np.nan, 0.8, 0.7, 0.6, 0.55])
    stale = np.isnan(dist)
    return {"t": t, "waypoint_index": idx, "distance": dist, "yaw_error_abs": np.full(10, 0.1),
            "yaw_error_rel": np.full(10, -0.2), "yaw_error": np.where(stale, np.nan, 0.05), "pose_stale": stale}


def test_metrics_from_plain_arrays_infer_the_reached_step():
    m = compute_metrics(WPS, fake_decisions(), {"t": [10, 11], "x": [0, 3], "y": [0, 4]}, "aborted", t0=10.0)
    w0, w1 = m["waypoints"]
    assert (w0["reached"], w0["time_to_reach_s"], w0["final_distance_m"]) == (True, 2.0, 0.3)
    assert w0["final_yaw_error_deg"] == pytest.approx(math.degrees(0.05))
    assert (w1["reached"], w1["time_to_reach_s"], w1["final_distance_m"], w1["min_distance_m"]) == \
        (False, None, 0.55, 0.55)
    assert (m["waypoints_reached"], m["all_reached"], m["stale_decisions"], m["path_length_m"]) == (1, False, 1, 5.0)
    assert m["outcome"] == "aborted"


def test_write_results_makes_every_file(tmp_path):
    traj = {"t": np.linspace(10, 20, 50), "x": np.linspace(0, 1, 50), "y": np.zeros(50)}
    paths = write_results(tmp_path / "out", WPS, traj, fake_decisions(), outcome="done", meta={"mission": "t"})
    for name in ("metrics", "decisions_csv", "trajectory_csv", "trajectory_png", "distance_png", "yaw_png",
                 "yaw_vs_distance_png"):
        assert paths[name].is_file() and paths[name].stat().st_size > 0, name
    metrics = json.loads(paths["metrics"].read_text())
    assert metrics["waypoints"][0]["reached"] is True
    assert paths["decisions_csv"].read_text().splitlines()[0].startswith("t,waypoint_index")


def test_write_results_names_a_missing_key(tmp_path):
    with pytest.raises(ValueError, match="decisions: missing key\\(s\\) yaw_error_rel"):
        d = fake_decisions()
        del d["yaw_error_rel"]
        write_results(tmp_path, WPS, {"t": [], "x": [], "y": []}, d)


def _start_writer(tmp_path, handle_sigterm):
    run_dir, ready = tmp_path / "run", tmp_path / "ready"
    proc = subprocess.Popen([sys.executable, str(HERE / "run_log_writer.py"), str(run_dir), str(ready),
                             "1" if handle_sigterm else "0"])
    deadline = time.monotonic() + 20.0
    while not ready.exists():
        assert proc.poll() is None, "writer exited early"
        assert time.monotonic() < deadline, "writer never became ready"
        time.sleep(0.05)
    return proc, run_dir


def test_killed_run_leaves_a_readable_bag_and_the_known_metrics(tmp_path):
    proc, run_dir = _start_writer(tmp_path, handle_sigterm=False)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["outcome"] == "running"            # the run never ended, what was known is there
    assert "if the process died this is where it stopped" in metrics["note"] and metrics["updated_at"]
    assert metrics["waypoints"][0]["reached"] is True and metrics["num_decisions"] >= 4
    # rosbag refuses the unindexed bag; read_run reindexes a copy and leaves the original untouched
    import rosbag
    with pytest.raises(rosbag.ROSBagUnindexedException):
        rosbag.Bag(str(run_dir / "run.bag"))
    size = (run_dir / "run.bag").stat().st_size
    run = read_run(run_dir / "run.bag")
    assert run["reindexed"] is True and run["meta"]["outcome"] == "interrupted"
    assert (run_dir / "run.bag").stat().st_size == size
    assert len(run["decisions"]["t"]) >= metrics["num_decisions"]
    assert len(run["trajectory"]["t"]) >= 50 * metrics["num_decisions"]
    assert run["waypoints"] == WPS
    # and the report CLI rebuilds the results folder from it
    out = tmp_path / "report"
    assert cli_main(["report", str(run_dir / "run.bag"), "--out", str(out)]) == 0
    rebuilt = json.loads((out / "metrics.json").read_text())
    assert rebuilt["outcome"] == "interrupted" and rebuilt["waypoints"][0]["reached"] is True
    assert rebuilt["waypoints"][0]["time_to_reach_s"] == pytest.approx(metrics["waypoints"][0]["time_to_reach_s"])
    assert (out / "yaw_errors.png").is_file()


def test_sigterm_closes_the_bag_and_writes_the_results(tmp_path):
    proc, run_dir = _start_writer(tmp_path, handle_sigterm=True)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=30) == 0
    import rosbag
    with rosbag.Bag(str(run_dir / "run.bag")) as bag:      # indexed: opens without reindexing
        assert bag.get_message_count("/tracking_status") >= 4
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["outcome"] == "aborted: SIGTERM"
    assert metrics["waypoints"][0]["reached"] is True and metrics["waypoints"][1]["reached"] is False
    for f in ("trajectory.png", "distance_error.png", "yaw_errors.png", "yaw_error_vs_distance.png",
              "decisions.csv", "mission.yaml"):
        assert (run_dir / f).is_file(), f


def test_report_cli_on_a_missing_bag(tmp_path, capsys):
    assert cli_main(["report", str(tmp_path / "nope.bag")]) == 1
    assert "no such file" in capsys.readouterr().err


@pytest.mark.parametrize("size", [0, 100])
def test_report_refuses_a_truncated_bag_naming_it(tmp_path, capsys, size):
    """A bag cut to its first bytes holds no run: exit 1 naming the bag, never "0/0 waypoints"."""
    log = RunLog(tmp_path / "run", "cut", WPS, t_start_s=0.0, mission_yaml="")
    log.add_decision(1.0, 0, 0, False, 1.0, 0.1, 0.2, 0.15)
    log.close("aborted: test", plots=False)
    bag = tmp_path / "cut.bag"
    bag.write_bytes((tmp_path / "run" / "run.bag").read_bytes()[:size])
    assert cli_main(["report", str(bag), "--out", str(tmp_path / "report"), "--no-plots"]) == 1
    captured = capsys.readouterr()
    assert str(bag) in captured.err and "0/0" not in captured.out
    assert not (tmp_path / "report" / "metrics.json").exists()


def test_a_decision_after_close_leaves_the_final_metrics(tmp_path):
    """A tracker step racing the shutdown must not turn the final outcome back into 'running'."""
    log = RunLog(tmp_path / "run", "race", [(1.0, 0.0, 0.0)], t_start_s=0.0, mission_yaml="")
    log.add_decision(1.0, 0, 0, False, 1.0, 0.1, 0.2, 0.15)
    log.close("aborted: SIGTERM", plots=False)
    log.add_decision(2.0, 0, 0, False, 0.9, 0.1, 0.2, 0.15)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["outcome"] == "aborted: SIGTERM"


def test_an_interrupted_run_says_so_live_and_in_its_report(tmp_path, capsys):
    """The process dies without close() (SIGKILL, simulated by dropping the log): metrics.json says it
    was written live and how to rebuild it; `report BAG` marks the run interrupted."""
    from geometry_msgs.msg import PoseStamped
    log = RunLog(tmp_path / "run", "killed", WPS, t_start_s=10.0, mission_yaml="waypoints: []\n")
    for k in range(3):
        msg = PoseStamped()
        msg.header.stamp.secs = 10 + k
        msg.pose.orientation.w = 1.0
        log.write("/com_pose", msg, 10.0 + k)
        log.add_decision(10.0 + k, 0, 0, False, 1.0 - 0.1 * k, 0.1, 0.2, 0.15)
    live = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert live["outcome"] == "running" and live["num_decisions"] == 3
    assert live["note"].startswith("written while the run was live; if the process died this is where it stopped")
    assert "snake_autonomy report " + str(tmp_path / "run" / "run.bag") in live["note"]
    assert time.strptime(live["updated_at"], "%Y-%m-%dT%H:%M:%S%z")
    del log                                            # no close(): the bag keeps no end event, no index
    out = tmp_path / "report"
    assert cli_main(["report", str(tmp_path / "run" / "run.bag"), "--out", str(out), "--no-plots"]) == 0
    assert "outcome interrupted" in capsys.readouterr().out
    rebuilt = json.loads((out / "metrics.json").read_text())
    assert rebuilt["outcome"] == "interrupted" and rebuilt["meta"]["mission"] == "killed"
    assert "no end of run" in rebuilt["meta"]["outcome_note"] and "note" not in rebuilt
    closed = RunLog(tmp_path / "closed", "done", WPS, t_start_s=0.0, mission_yaml="")
    closed.add_decision(1.0, 0, 0, False, 1.0, 0.1, 0.2, 0.15)
    closed.close("aborted: test", plots=False)
    final = json.loads((tmp_path / "closed" / "metrics.json").read_text())
    assert final["outcome"] == "aborted: test" and "note" not in final


def test_scout_events_reach_the_metrics_of_the_ros_path(tmp_path):
    """The mission node logs each finished scout stop as a run event; the results rebuilt from the bag
    list them under `scouts` (top level, as the batch simulator's metrics do)."""
    log = RunLog(tmp_path / "run", "scouting", [(1.0, 0.0, 0.0)], t_start_s=0.0, mission_yaml="")
    log.add_decision(1.0, 0, 0, False, 1.0, 0.1, 0.2, 0.15)
    log.event({"event": "scout", "waypoint_index": 0, "outcome": "done", "planned_head_height_m": 0.3}, 2.0)
    log.event({"event": "scout", "waypoint_index": 0, "outcome": "failed: no plan"}, 3.0)
    log.close("done: every waypoint reached", plots=False)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert [s["outcome"] for s in metrics["scouts"]] == ["done", "failed: no plan"]
    assert metrics["scouts"][0]["planned_head_height_m"] == 0.3
    assert "scouts" not in metrics["meta"]


def test_path_length_counts_progress_not_the_sway_of_a_100_hz_stream(tmp_path):
    """A CoM moving 1 m along x at 100 Hz with a 2 cm sawtooth across it (the base pose refreshing
    slower than the joints): about 1 m (a counted 5 cm step still carries up to 2 cm across: +8 %),
    not the 20 m of the raw sum (the demo's star, 12.9 m of legs, came to 129 m raw, 22 m now)."""
    t = np.arange(0.0, 10.0, 0.01)
    x, y = t / 10.0, 0.02 * (np.arange(len(t)) % 2)
    assert 1.0 <= path_length({"x": x, "y": y}) < 1.1
    log = RunLog(tmp_path / "run", "sway", [(1.0, 0.0, 0.0)], t_start_s=0.0, mission_yaml="")
    for ti, xi, yi in zip(t, x, y):
        log.add_pose(float(ti), float(xi), float(yi))
    assert log.path_length_m == pytest.approx(path_length({"x": x, "y": y}))
    log.close("done", plots=False)


def test_the_simulators_ground_truth_com_is_not_read_as_the_estimate(tmp_path):
    """/ground_truth/com_pose shares the last name of /com_pose; interleaved, the trajectory zig-zagged
    between the two (the demo's star report measured 260 m)."""
    from geometry_msgs.msg import PoseStamped
    log = RunLog(tmp_path / "run", "truth", [(1.0, 0.0, 0.0)], t_start_s=0.0, mission_yaml="")
    for k in range(20):
        for topic, y in (("/com_pose", 0.0), ("/ground_truth/com_pose", 0.3)):
            msg = PoseStamped()
            msg.header.stamp = rospy_time(0.1 * k + (0.05 if y else 0.0))
            msg.pose.position.x, msg.pose.position.y, msg.pose.orientation.w = 0.05 * k, y, 1.0
            log.write(topic, msg, 0.1 * k)
    log.close("done", plots=False)
    run = read_run(tmp_path / "run" / "run.bag")
    assert len(run["trajectory"]["y"]) == 20 and not np.any(run["trajectory"]["y"])


def rospy_time(t_s):
    import genpy
    return genpy.Time.from_sec(t_s)
