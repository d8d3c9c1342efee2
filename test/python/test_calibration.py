"""`snake_autonomy calibrate`: the eq. 3.31 analysis on synthetic data, the shared sequence (hold at
the end, on a stale pose, on Ctrl-C) with a fake robot and with the ROS back-end's RosRobot on a fake
publisher, the YAML the tracker reads, and the simulated robot's calibration against config/sim.yaml
(fails when the plant drifts from its calibration)."""
import math
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import yaml

from snake_autonomy.calibration.analysis import CalibrationError, Segment, fit
from snake_autonomy.calibration.output import write_yaml
from snake_autonomy.calibration.ros_backend import RosRobot
from snake_autonomy.calibration.sequence import Plan, run_plan
from snake_autonomy.missions import load_defaults, read_overrides

ROOT = Path(__file__).resolve().parents[2]
PERIOD = 1 / 0.35


def synthetic_segment(delta_deg, drift=-6.0, gain=0.8, offset_deg=81.0, offset_per_deg=0.5, speed=0.24,
                      cycles=6, rate_hz=50.0, noise_deg_s=0.0, rng=None, run="synthetic", yaw0=0.3):
    """com_pose samples of a robot turning at drift + gain * delta deg/s, travelling at offset_deg (+
    offset_per_deg per degree of delta) from its chassis axis, with the gait's oscillation on top."""
    rate = math.radians(drift + gain * delta_deg + (rng.normal(0, noise_deg_s) if rng is not None else 0.0))
    offset = math.radians(offset_deg + offset_per_deg * delta_deg)
    t = np.arange(0.0, cycles * PERIOD + 1e-9, 1.0 / rate_hz)
    phase = 2 * math.pi * t / PERIOD
    yaw = yaw0 + rate * t + 0.15 * np.sin(phase)                  # the chassis wobbles every cycle
    heading = yaw0 + rate * t + offset                             # the mean motion
    dt = np.diff(t, prepend=t[0])
    x = np.cumsum(speed * np.cos(heading) * dt) + 0.02 * np.sin(2 * phase)
    y = np.cumsum(speed * np.sin(heading) * dt) + 0.02 * np.cos(phase)
    return Segment(delta_deg, PERIOD, np.column_stack([t + 100.0, x, y, yaw]), run)


def test_eq_3_31_fit_recovers_drift_gain_and_heading_offset():
    r = fit([synthetic_segment(d) for d in (-2.0, 0.0, 2.0, 4.0)])
    assert r.drift_rate_deg_s == pytest.approx(-6.0, abs=0.05)
    assert r.steering_gain_deg_s_per_deg == pytest.approx(0.8, abs=0.01)
    assert r.k_bias_s == pytest.approx(1 / 0.8, rel=0.02)
    assert r.delta_offset_deg == pytest.approx(7.5, abs=0.1)             # -K_bias * drift = 6 / 0.8
    assert r.heading_offset_deg == pytest.approx(81.0 + 0.5 * 7.5, abs=1.0)
    assert r.rate_residual_std_deg_s < 0.05 and r.warnings               # 7.5 is outside [-2, 4]: extrapolated
    assert all(s.cycles == 6 for s in r.segments)
    two = fit([synthetic_segment(d) for d in (0.0, 4.0)])                 # a line through two points:
    assert two.delta_offset_deg == pytest.approx(7.5, abs=0.1)            # a value, but no scatter
    assert math.isnan(two.rate_residual_std_deg_s) and math.isnan(two.delta_offset_std_deg)


def test_two_deltas_say_there_is_no_spread_instead_of_nan():
    summary = fit([synthetic_segment(d) for d in (0.0, 4.0)]).summary()
    assert "nan" not in summary.lower()
    assert "no spread with 2 segments (3 or more needed)" in summary


@pytest.mark.parametrize("deltas, message", [("a,b", "--deltas: expected degrees separated by commas, got 'a,b'"),
                                             ("0,,5", "--deltas: expected degrees separated by commas, got '0,,5'"),
                                             ("0,inf", "--deltas: must be finite, got '0,inf'"),
                                             ("5", "--deltas: need two different values or more, got '5'")])
def test_calibrate_deltas_errors_name_the_option_and_value(tmp_path, capsys, deltas, message):
    from snake_autonomy.cli import main as cli_main
    assert cli_main(["calibrate", "--sim", "--out", str(tmp_path / "out"), "--deltas", deltas]) == 2
    assert message in capsys.readouterr().err


def test_fit_scatter_and_per_run_values_on_noisy_runs():
    rng = np.random.default_rng(1)
    segs = [synthetic_segment(d, noise_deg_s=0.3, rng=rng, run=f"seed {k}", yaw0=k)
            for k in range(3) for d in (4.0, 6.0, 8.0, 10.0)]
    r = fit(segs)
    assert r.delta_offset_deg == pytest.approx(7.5, abs=1.0) and not r.warnings
    assert 0.1 < r.rate_residual_std_deg_s < 0.6                         # the injected 0.3 deg/s
    assert 0.05 < r.delta_offset_std_deg < 1.0
    assert sorted(r.per_run_delta_offset_deg) == ["seed 0", "seed 1", "seed 2"]
    assert "delta_offset (eq. 3.31)" in r.summary()


def test_fit_refuses_what_cannot_be_calibrated():
    with pytest.raises(CalibrationError, match="two different delta"):
        fit([synthetic_segment(0.0), synthetic_segment(0.0)])
    with pytest.raises(CalibrationError, match="no measurable effect"):
        fit([synthetic_segment(d, gain=0.0) for d in (0.0, 2.0)])
    with pytest.raises(CalibrationError, match="times must increase"):
        seg = synthetic_segment(0.0)
        seg.samples[5, 0] = seg.samples[4, 0]
        fit([seg, synthetic_segment(2.0)])


class FakeRobot:
    """Poses at 100 Hz of a robot that turns at -6 + 0.8 delta deg/s once commanded; optionally
    silent (stale) or interrupted (Ctrl-C) from a given time."""

    def __init__(self, stale_after_s=None, interrupt_after_s=None, first_pose=True):
        self.t, self.yaw, self.x, self.y = 0.0, 0.0, 0.0, 0.0
        self.rate_deg_s, self.moving = 0.0, False
        self.log = []
        self.stale_after_s, self.interrupt_after_s, self.first_pose = stale_after_s, interrupt_after_s, first_pose

    def command(self, gait, steer, delta_rad):
        self.log.append((round(self.t, 2), gait, steer, round(math.degrees(delta_rad), 6)))
        self.moving = gait == "sidewind"
        self.rate_deg_s = -6.0 + 0.8 * math.degrees(delta_rad) if self.moving else 0.0
        return ""

    def next_pose(self, timeout_s):
        if not self.first_pose:
            return None
        if self.interrupt_after_s is not None and self.t >= self.interrupt_after_s:
            raise KeyboardInterrupt
        if self.stale_after_s is not None and self.t >= self.stale_after_s:
            return None
        self.t += 0.01
        if self.moving:
            self.yaw += math.radians(self.rate_deg_s) * 0.01
            self.x += 0.24 * math.cos(self.yaw + 1.4) * 0.01
            self.y += 0.24 * math.sin(self.yaw + 1.4) * 0.01
        return self.t, self.x, self.y, self.yaw


def plan():
    return Plan(deltas_deg=[0.0, 2.0, 4.0], period_s=PERIOD, settle_cycles=1, record_cycles=2, resend_s=0.5)


def test_sequence_runs_every_delta_resends_and_holds_at_the_end():
    robot = FakeRobot()
    out = run_plan(robot, plan(), log=lambda m: None)
    assert out.stopped == "" and [s.delta_deg for s in out.segments] == [0.0, 2.0, 4.0]
    assert robot.log[-1][1] == "hold" and not robot.moving
    sidewinds = [c for c in robot.log if c[1] == "sidewind"]
    assert all(c[2] for c in sidewinds)                                   # steer on, at the planned deltas
    assert [c[3] for c in sidewinds if c[0] < 2.0][0] == 0.0
    per_segment = 3 * PERIOD / 0.5                                        # heartbeat every 0.5 s
    assert len(sidewinds) >= 3 * (per_segment - 1)
    seg = out.segments[1]
    assert seg.samples[-1, 0] - seg.samples[0, 0] == pytest.approx(2 * PERIOD, abs=0.02)
    assert fit(out.segments).delta_offset_deg == pytest.approx(7.5, abs=0.05)


def test_sequence_holds_on_stale_pose_on_ctrl_c_on_a_still_robot_and_never_moves_without_a_pose():
    stale = FakeRobot(stale_after_s=1.5 * 3 * PERIOD)                   # in the second delta
    out = run_plan(stale, plan(), log=lambda m: None)
    assert "stale pose" in out.stopped and len(out.segments) == 1
    assert stale.log[-1][1] == "hold" and not stale.moving
    ctrl_c = FakeRobot(interrupt_after_s=2.0)
    out = run_plan(ctrl_c, plan(), log=lambda m: None)
    assert out.stopped == "interrupted (Ctrl-C)" and out.segments == []
    assert ctrl_c.log[-1][1] == "hold" and not ctrl_c.moving
    stuck = FakeRobot()
    stuck.command = lambda gait, steer, delta: stuck.log.append((round(stuck.t, 2), gait)) or ""   # never moves
    out = run_plan(stuck, plan(), log=lambda m: None)
    assert "did not move" in out.stopped and out.segments == [] and stuck.log[-1][1] == "hold"
    blind = FakeRobot(first_pose=False)
    out = run_plan(blind, plan(), start_timeout_s=0.01, log=lambda m: None)
    assert "no pose" in out.stopped and [c[1] for c in blind.log] == ["hold"]


def test_ros_backend_sequencing_with_a_fake_publisher_and_pose_source():
    """RosRobot (the ROS back-end without rospy): commands go to the publisher, poses pushed from another
    thread (as rospy's callbacks) are consumed in order; when they stop, the robot is held."""
    sent = []
    robot = RosRobot(lambda gait, steer, delta: sent.append((gait, steer, delta)))
    fake = FakeRobot()
    stop_at = 1.5 * 3 * PERIOD
    got_command = threading.Event()

    def source():
        got_command.wait(5.0)
        while fake.t < stop_at:
            fake.rate_deg_s = -6.0 + 0.8 * math.degrees(sent[-1][2]) if sent else 0.0
            fake.moving = True
            robot.on_pose(*fake.next_pose(1.0))
    pusher = threading.Thread(target=source, daemon=True)
    robot.on_pose(0.0, 0.0, 0.0, 0.0)                                     # the first pose: ready
    real_command = robot.command

    def command(gait, steer, delta):
        why = real_command(gait, steer, delta)
        got_command.set()
        return why
    robot.command = command
    pusher.start()
    out = run_plan(robot, plan(), pose_timeout_s=0.3, log=lambda m: None)
    pusher.join(5.0)
    assert "stale pose" in out.stopped and len(out.segments) == 1
    assert sent[0][:2] == ("sidewind", True) and sent[-1] == ("hold", False, 0.0)
    assert robot.next_pose(0.01) is None


def test_calibration_yaml_is_what_the_tracker_reads(tmp_path):
    r = fit([synthetic_segment(d) for d in (6.0, 8.0)])
    path = write_yaml(tmp_path / "calibration.yaml", r, {"backend": "test"})
    overrides = read_overrides(path)
    assert overrides == {"delta0_deg": round(r.delta_offset_deg, 1),
                         "heading_offset_deg": round(r.heading_offset_deg, 1)}
    d = load_defaults(overrides=overrides, overrides_source=str(path))
    assert d["tracker"]["delta0"] == pytest.approx(math.radians(overrides["delta0_deg"]))
    assert d["heading_offset_deg"] == overrides["heading_offset_deg"]
    assert yaml.safe_load(path.read_text())["calibration"]["segments"][0]["delta_deg"] == 6.0


def test_simulated_robot_calibration_matches_config_sim_yaml(tmp_path):
    """`snake_autonomy calibrate --sim` on two seeds (about 30 s): the measured straight-sidewinding delta
    and heading offset stay within tolerance of config/sim.yaml's tracker: delta0_deg and
    heading_offset_deg. Fails when the plant, the gaits or the driver change and nobody re-calibrates
    (`snake_autonomy calibrate --sim --seeds 0-4`, README). Tolerances: the seeds' own spread."""
    out = tmp_path / "cal"
    rc = subprocess.call([sys.executable, str(ROOT / "scripts" / "snake_autonomy"), "calibrate", "--sim",
                          "--seeds", "0-1", "--deltas", "4,7,10", "--settle-cycles", "2", "--cycles", "3",
                          "--out", str(out)], stdout=subprocess.DEVNULL)
    assert rc == 0
    measured = yaml.safe_load((out / "calibration.yaml").read_text())
    configured = yaml.safe_load((ROOT / "config" / "sim.yaml").read_text())["tracker"]
    assert measured["tracker"]["delta0_deg"] == pytest.approx(configured["delta0_deg"], abs=1.5)
    assert measured["tracker"]["heading_offset_deg"] == pytest.approx(configured["heading_offset_deg"], abs=2.0)
    assert (out / "calibration.png").stat().st_size > 10000
