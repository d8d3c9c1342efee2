"""The batch runner: closed loop on the simulated robot without ROS (sim.batch, sim.experiments).

Kept small for `make test` (about 20 s): the single-waypoint experiment on two seeds and two of its
13 start poses (one behind the waypoint, one in front); the full sweeps are `snake_autonomy sim
experiment ...` (README)."""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.control import WaypointTracker
from snake_autonomy.missions import MissionError, load_defaults
from snake_autonomy.runs.batch import BatchRun, RunSpec, load_driver_config
from snake_autonomy.sim.disturbances import parse_triggers
from snake_autonomy.runs.mission_experiment import SINGLE_STARTS, run_experiment

ROOT = Path(__file__).resolve().parents[2]
SHORT = str(ROOT / "test" / "ros" / "missions" / "sim_short.yaml")


def test_single_waypoint_experiment_two_seeds(tmp_path):
    """Every run reaches the waypoint within d_th and psi_wp, no roll-over, no goal beyond a limit;
    the summary table and figure are written."""
    summary = run_experiment("single", [0, 1], "mocap", tmp_path, starts=[1, 6], progress=False)
    assert summary["runs"] == 4 and summary["accepted"], summary["failed_runs"]
    assert summary["rolled_over"] == 0 and summary["limit_violations"] == 0
    assert summary["final_distance_m"]["max"] <= 0.35
    assert summary["final_yaw_error_deg"]["max"] <= 30.0
    out = tmp_path / "mocap"
    for name in ("summary.json", "summary.md", "summary.png"):
        assert (out / name).is_file()
    m = json.loads((out / "seed0_start01" / "metrics.json").read_text())
    assert m["start"] == list(SINGLE_STARTS[1])
    assert (out / "seed0_start01" / "trajectory.png").is_file()


def test_sim_run_cli_metrics_contract(tmp_path):
    """`snake_autonomy sim run` writes metrics.json with the keys checks rely on; VIO feedback goes
    through the pose remapper and gets evaluated against the plant's camera pose."""
    out = tmp_path / "run"
    rc = subprocess.call([sys.executable, str(ROOT / "scripts" / "snake_autonomy"), "sim", "run", "--mission", SHORT,
                          "--seed", "2", "--feedback", "vio", "--out", str(out), "--start", "0,0,0",
                          "--time-limit", "40", "--no-progress"])
    m = json.loads((out / "metrics.json").read_text())
    assert rc == 0, m["outcome"]
    for key, kind in (("rolled_over", bool), ("limit_violations", int), ("sim_time_s", float)):
        assert isinstance(m[key], kind)
    assert m["limit_violations"] == 0 and m["rolled_over"] is False
    w = m["waypoints"][0]
    assert w["reached"] is True and isinstance(w["time_s"], float)
    assert w["final_distance_m"] <= 0.35 and abs(w["final_yaw_error_deg"]) <= 30.0
    assert m["vio"]["samples"] > 100
    assert m["vio_evaluation"]["ape_translation_m"]["rmse"] < 0.2
    assert (out / "trajectory.png").is_file() and (out / "evaluation" / "stats.json").is_file()


def test_sim_run_cli_input_errors(tmp_path):
    """A refused mission or option is one message and exit 1 (2 stays argparse's usage error)."""
    cli = [sys.executable, str(ROOT / "scripts" / "snake_autonomy"), "sim", "run", "--out", str(tmp_path)]
    assert subprocess.call(cli + ["--mission", "no_such_mission"], stderr=subprocess.DEVNULL) == 1
    assert subprocess.call(cli + ["--mission", SHORT, "--start", "1,2"], stderr=subprocess.DEVNULL) == 1
    assert subprocess.call(cli + ["--mission", SHORT, "--seed", "x"], stderr=subprocess.DEVNULL) == 2


def test_batch_run_deterministic_per_seed():
    """Same seed, same everything: the same decisions and path; another seed: another path."""
    def run(seed):
        r = BatchRun(RunSpec(mission=SHORT, seed=seed, time_limit_s=8.0)).run()
        return r.decisions, r.trajectory
    (d1, t1), (d2, t2), (_, t3) = run(4), run(4), run(5)
    assert d1["gait"] == d2["gait"] and d1["distance"] == d2["distance"]
    assert np.array_equal(t1["x_true"], t2["x_true"]) and np.array_equal(t1["y_true"], t2["y_true"])
    assert not np.array_equal(t1["x_true"], t3["x_true"])


def _controller(**config):
    """The bound C++ DriverController on a FakeServoBus whose present values stay where the test puts them."""
    robot = _core.RobotModel.from_yaml(str(ROOT / "config" / "robots" / "cobra.yaml"))
    library = _core.GaitLibrary.from_yaml(str(ROOT / "config" / "gaits.yaml"))
    table = _core.dynamixel.ControlTable.from_yaml(str(ROOT / "config" / "dynamixel" / "xh540_w270.yaml"))
    bus = _core.dynamixel.FakeServoBus(table, robot.servo_ids)
    bus.set_follow_goal(False)
    return robot, bus, _core.DriverController(robot, library, table, bus, _core.DriverConfig(**config))


def test_driver_controller_holds_on_stale_pose_and_keeps_goals_in_limits():
    robot, bus, drv = _controller(pose_timeout_s=0.5, command_timeout_s=0.0)  # one command for 6 s
    assert "torque is off" in drv.command_gait(gait="sidewind")      # refused before start
    drv.start(0.0)
    assert drv.state == "holding" and all(bus.servos.get(i, "torque_enable") == 1 for i in robot.servo_ids)
    assert drv.command_gait(gait="sidewind", steer=True, delta_rad=math.radians(20)) == ""
    assert "unknown gait" in drv.command_gait(gait="moonwalk")
    assert "not steerable" in drv.command_gait(gait="turn_left", steer=True, delta_rad=0.1)
    moving = []
    last_pose = None
    prev = drv.goal_rad
    for k in range(1, 600):
        t = k * 0.01
        if t < 3.0:
            assert drv.set_base_pose(t, [0, 0, 0], [0, 0, 0, 1])
            last_pose = t
        assert drv.update(t, 0.01)
        goal = drv.goal_rad
        assert np.all(goal <= robot.joint_upper_rad + 1e-12) and np.all(goal >= robot.joint_lower_rad - 1e-12)
        assert np.all(np.abs(goal - prev) <= 4.5 * 0.01 + 1e-9)          # the slew limit
        ticks = np.array([bus.servos.get(i, "goal_position") for i in robot.servo_ids])
        assert np.all(np.abs(np.array([drv.ticks_to_joint_rad(j, int(v)) for j, v in enumerate(ticks)]) - goal)
                      <= math.pi / 4096 + 1e-12)                          # written to the bus, rounded to ticks
        prev = goal
        moving.append(np.max(np.asarray(drv.cpg.amplitudes)))
        assert drv.pose_fresh == (t - last_pose <= 0.5 + 1e-9)            # com_pose only while fresh
    assert drv.state == "running" and drv.locomotion_gated
    assert moving[250] > 0.5                     # sidewinding before the pose went stale
    assert moving[-1] < 0.05                     # amplitudes decayed: locomotion held (ERRATA #7)
    assert drv.set_base_pose(6.0, [0, 0, 0], [0, 0, 0, 0]) is False   # no length: ignored


def test_load_driver_config_takes_the_controllers_keys_of_driver_yaml(tmp_path):
    """The batch path reads the same driver.yaml as driver_node: every controller key, the node's
    own keys (port, rate, frames) ignored, bad values refused naming the key."""
    cfg = load_driver_config(str(ROOT / "config" / "driver.yaml"))
    assert cfg.return_delay_time_us == 0 and cfg.max_failed_cycles == 10 and cfg.fault_action == "hold"
    f = tmp_path / "driver.yaml"
    f.write_text("rate_hz: 250.0\nbase_frame: b\nreturn_delay_time_us: -1\nmax_failed_cycles: 4\n"
                 "fault_action: torque_off\nrequire_pose: false\n")
    cfg = load_driver_config(str(f))
    assert (cfg.return_delay_time_us, cfg.max_failed_cycles, cfg.fault_action, cfg.require_pose) == \
        (-1, 4, "torque_off", False)
    f.write_text("return_delay_time_us: 3\n")
    with pytest.raises(ValueError, match="return_delay_time_us: 3"):
        load_driver_config(str(f))


def test_batch_driver_has_the_same_command_lifetime_as_driver_node(tmp_path):
    """command_timeout_s comes from driver.yaml on the batch path too, and expires on the loop's
    (simulated) clock: a running gait without commands holds, with the reason; the next resumes."""
    assert load_driver_config(str(ROOT / "config" / "driver.yaml")).command_timeout_s == 3.0
    with pytest.raises(ValueError, match="command_timeout_s: -1"):
        _core.DriverConfig(command_timeout_s=-1.0)
    robot, bus, drv = _controller(command_timeout_s=1.0, require_pose=False)
    drv.start(0.0)
    assert drv.command_gait(gait="sidewind") == ""
    states = []
    for k in range(1, 151):
        drv.update(k * 0.01, 0.01)
        states.append(drv.state)
    assert states[99] == "running" and states[-1] == "holding"
    assert "command_timeout_s" in drv.hold_reason
    assert drv.command_gait(gait="sidewind") == ""
    drv.update(1.51, 0.01)
    assert drv.state == "running" and drv.hold_reason == ""


def test_driver_controller_binding_config_faults_and_lifetime():
    with pytest.raises(ValueError, match="max_joint_velocity_rad_s"):
        _core.DriverConfig(max_joint_velocity_rad_s=-1.0)
    with pytest.raises(ValueError, match="fault_action"):
        _core.DriverConfig(fault_action="explode")
    assert _core.DriverConfig(pose_timeout_s=0.25).pose_timeout_s == 0.25
    with pytest.raises(ValueError, match="return_delay_time_us: 7"):
        _core.DriverConfig(return_delay_time_us=7)
    robot, bus, drv = _controller(max_failed_cycles=3)
    del bus                                       # the controller keeps its bus alive
    import gc
    gc.collect()
    drv.start(0.0)
    drv.set_base_pose(0.0, [1.0, 2.0, 0.0], [0, 0, 0, 1])
    assert drv.update(0.01, 0.01)
    ref = _core.Kinematics(robot).compute([1.0, 2.0, 0.0], [0, 0, 0, 1], np.zeros(robot.num_joints))
    assert np.allclose(drv.com, ref.com) and np.allclose(drv.vc_rotation, ref.vc_rotation)
    assert drv.com_yaw == pytest.approx(math.atan2(ref.vc_rotation[1, 0], ref.vc_rotation[0, 0]))
    robot2, bus2, drv2 = _controller(max_failed_cycles=3)
    drv2.start(0.0)
    bus2.servos.set_silent(robot2.servo_ids[4], True)
    for k in range(1, 4):
        assert drv2.update(k * 0.01, 0.01) is False
    assert drv2.state == "fault" and "servo 5" in drv2.fault_reason


def test_far_blend_max_gap_steers_on_the_bearing_behind_the_waypoint():
    """Behind the waypoint (heading 0, robot at +1.2 m facing it): Algorithm 1 as printed blends the
    opposite headings into a perpendicular error; with the gap limit the bearing alone steers."""
    literal = WaypointTracker([(0.0, 0.0, 0.0)])
    gapped = WaypointTracker([(0.0, 0.0, 0.0)], far_blend_max_gap=math.radians(90))
    _, _, _, w, e = literal.errors(1.2, 0.05, math.pi, 0)
    assert w > 0.1 and abs(e) > math.radians(40)              # would turn away from the waypoint
    _, _, rel, w, e = gapped.errors(1.2, 0.05, math.pi, 0)
    assert w == 0.0 and e == pytest.approx(rel) and abs(e) < math.radians(5)
    assert gapped.errors(0.2, 0.0, math.pi, 0)[3] > 0.5        # NEAR branch: the blend as printed


def test_tracker_overrides_and_disturbance_triggers_are_checked():
    d = load_defaults(overrides={"delta0_deg": 7.0, "heading_offset_deg": 81.0})
    assert d["tracker"]["delta0"] == pytest.approx(math.radians(7.0)) and d["heading_offset_deg"] == 81.0
    with pytest.raises(MissionError, match="delta_zero_deg: unknown key"):
        load_defaults(overrides={"delta_zero_deg": 7.0})
    with pytest.raises(ValueError) as exc:
        parse_triggers([{"link": "link_6", "force_n": [0, 1], "waypoint": 3, "distance_m": -1}], 2)
    text = str(exc.value)
    assert "force_n: expected 3 numbers" in text and "waypoint" in text and "distance_m: must be > 0" in text
