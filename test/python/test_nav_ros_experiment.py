"""`snake_autonomy nav ros-experiment` without ROS: the comparison table and its outcome rule, the
watcher's end rules, the batch run's time counted as the ROS run counts it, the launch's shutdown
(a process group of its own, nothing left behind) and the command's refusals (exit 2, nothing run).
The ROS path itself (sim.launch per world) is run by hand: docs/navigation.md."""
import subprocess
import sys
import time
from pathlib import Path

import pytest

from snake_autonomy.cli import main as cli_main
from snake_autonomy.runs.nav_ros_experiment import (_alive, _group_alive, check_robot, comparison_row,
                                                    comparison_table, descendants, moving_time_s, same_outcome,
                                                    shut_down)
from snake_autonomy.runs.nav_ros_watch import Watch

OK = {"goal_reached": True, "collisions": 0, "time_s": 130.0, "end": "goal_reached"}


def test_same_outcome_is_success_in_both_or_in_neither():
    touched = {**OK, "collisions": 1}
    missed = {"goal_reached": False, "collisions": 0}
    assert same_outcome(OK, OK)
    assert same_outcome(touched, missed)           # neither a success
    assert not same_outcome(OK, touched)
    assert not same_outcome(missed, OK)
    assert not same_outcome({**OK, "collisions": None}, OK)   # no contact count from sim_node: not a success


def test_the_table_has_one_row_per_world_and_seed_and_counts_the_same_outcomes():
    rows = [comparison_row("a", 0, OK, {**OK, "time_from_move_s": 125.4, "outcome": "success"}),
            comparison_row("b", 3, {"goal_reached": False, "collisions": 2, "time_s": 200.0, "end": "time_limit"},
                           {**OK, "time_from_move_s": 140.0, "outcome": "success"})]
    table = comparison_table(rows)
    lines = table.splitlines()
    assert lines[0].startswith("| world | seed | ROS: reached | ROS: contacts | ROS: time (s) | batch: reached")
    assert lines[2] == "| a | 0 | yes | 0 | 130 | yes | 0 | 125 | yes |"
    assert lines[3] == "| b | 3 | no | 2 | 200 (time_limit) | yes | 0 | 140 | no |"
    assert lines[-1].endswith("1 of 2 runs")


def test_a_ros_run_the_launch_cut_short_is_not_compared():
    batch = {**OK, "time_from_move_s": 764.0, "outcome": "success"}
    stopped = {"goal_reached": False, "collisions": 0, "time_s": 45.4,
               "end": "launch_stopped: /robot_state_publisher gone with roslaunch"}
    rows = [comparison_row("a", 0, OK, batch), comparison_row("b", 0, stopped, batch)]
    assert rows[1]["same_outcome"] is None
    lines = comparison_table(rows).splitlines()
    assert lines[3].endswith("| 764 | - |")
    assert lines[-1].endswith("1 of 1 runs (1 more cut short by the launch, not compared)")
    died = {**stopped, "end": "node_died: /planner"}      # a node that died is an outcome: compared
    assert comparison_row("b", 0, died, batch)["same_outcome"] is False


def test_the_batch_time_counts_from_the_first_command_that_moves():
    commands = [(0.5, "hold_curve", 0.0, "waiting"), (1.0, "hold_curve", 0.0, "waiting"),
                (1.5, "rectilinear", 0.1, "following"), (90.0, "hold_curve", 0.0, "goal_reached")]
    assert moving_time_s(commands, 90.0, 100.0, ("hold", "hold_curve")) == 88.5
    assert moving_time_s(commands, None, 100.0, ("hold", "hold_curve")) == 98.5
    assert moving_time_s(commands[:2], None, 100.0, ("hold", "hold_curve")) is None


def test_the_watch_ends_after_settling_at_the_goal_and_decides_by_the_final_pose():
    w = Watch((1.0, 0.0), 0.15, time_limit_s=100.0, settle_s=10.0, startup_s=50.0, t0=0.0)
    w.on_command(5.0, "hold_curve")
    assert w.step(20.0) is None and w.t_move is None
    w.on_command(21.0, "rectilinear")
    w.on_planner(80.0, {"state": "goal_reached"})
    assert w.result(82.0)["replans_without_joints"] is None
    w.on_planner(85.0, {"state": "goal_reached", "replans": "7", "replans_without_joints": "2"})
    assert w.step(89.0) is None
    w.on_truth(0.9, 0.05)
    w.on_sim({"obstacle_contacts": "0", "min_clearance_m": "0.120"})
    assert w.step(90.0) == "goal_reached"
    r = w.result(90.5)
    assert (r["goal_reached"], r["loop_reached"], r["time_s"], r["collisions"]) == (True, True, 59.0, 0)
    assert (r["replans"], r["replans_without_joints"]) == (7, 2)
    w.on_truth(1.3, 0.0)                           # the hold left the disc: not reached
    assert w.result(91.0)["goal_reached"] is False


def test_the_watch_ends_at_the_time_limit_without_a_start_or_when_a_node_dies():
    w = Watch((1.0, 0.0), 0.15, time_limit_s=100.0, startup_s=50.0, t0=0.0)
    assert w.step(49.0) is None
    assert w.step(50.0) == "no_start"
    w = Watch((1.0, 0.0), 0.15, time_limit_s=100.0, t0=0.0)
    w.on_command(10.0, "rectilinear")
    w.on_planner(105.0, {"state": "goal_reached"})  # the settle is cut at the limit, as the batch run's
    assert w.step(109.0) is None
    assert w.step(110.0) == "time_limit"
    assert w.result(111.0)["time_s"] == 95.0
    w = Watch((1.0, 0.0), 0.15, time_limit_s=100.0, t0=0.0)
    assert w.step(3.0, dead="/planner") == "node_died: /planner"


def test_shutdown_leaves_no_process_of_the_launch_not_even_in_a_session_of_its_own():
    # as roslaunch: ignores SIGINT here, a child in its group, a child in a session of its own (a node)
    proc = subprocess.Popen([sys.executable, "-c", "import signal, subprocess, time\n"
                             "signal.signal(signal.SIGINT, signal.SIG_IGN)\n"
                             "subprocess.Popen(['sleep', '60'])\n"
                             "subprocess.Popen(['sleep', '60'], start_new_session=True)\n"
                             "time.sleep(60)"], start_new_session=True)
    deadline = time.monotonic() + 10.0
    while len(descendants(proc.pid)) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    below = descendants(proc.pid)
    assert len(below) == 2
    t0 = time.monotonic()
    ended = shut_down(proc, timeout_s=1.0)        # SIGINT ignored: SIGKILL to the group and each pid
    assert ended["survivors"] == [] and not _group_alive(proc.pid)
    assert not any(Path(f"/proc/{p}").exists() and _alive(p, s) for p, s in below.items())
    assert ended["shutdown"] == "sigint+sigkill" and time.monotonic() - t0 < 10.0


def test_only_the_simulated_robot_is_accepted():
    check_robot("cobra")
    check_robot("chang_rectilinear")
    with pytest.raises(ValueError, match="simulates cobra, chang_rectilinear only"):
        check_robot("unified_snake")


@pytest.mark.parametrize("extra, message", [
    (["--world-files", "{tmp}/none-*.yaml"], "no file matches"),
    (["--world-files", "{root}/test/ros/worlds/sim_nav.yaml", "--robot", "unified_snake"],
     "simulates cobra, chang_rectilinear only"),
    (["--family", "barn", "--world-files", "{root}/test/ros/worlds/sim_nav.yaml"], "one or the other"),
    (["--world-files", "{root}/test/ros/worlds/sim_nav.yaml", "--time-limit", "-5"], "--time-limit"),
    (["--world-files", "{root}/test/ros/worlds/sim_nav.yaml", "--seeds", "x"], "--seeds"),
])
def test_bad_arguments_exit_2_before_anything_runs(tmp_path, root, capsys, extra, message):
    out = tmp_path / "out"
    args = [a.format(tmp=tmp_path, root=root) for a in extra]
    assert cli_main(["nav", "ros-experiment", *args, "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_the_watch_writes_commands_and_track_from_the_first_move(tmp_path):
    w = Watch((1.0, 0.0), 0.15, time_limit_s=100.0, t0=0.0)
    w.on_command(4.0, "hold_curve", 0.0)
    w.on_command(5.0, "rectilinear", -1.5)
    w.on_truth(0.1, 0.0)
    w.step(6.0)
    w.write_csv(tmp_path)
    assert (tmp_path / "commands.csv").read_text().splitlines() == [
        "t_s,gait,kappa_per_m", "-1.00,hold_curve,0.0000", "0.00,rectilinear,-1.5000"]
    assert (tmp_path / "trajectory.csv").read_text().splitlines() == ["t_s,x_m,y_m", "1.00,0.1000,0.0000"]
