"""The batch simulator's `vo` pose source (sim/vo_feedback.py): the visual-inertial odometry on the
head camera's rendered frames and the IMU, through the tracking gate and eq. 3.1 into the driver.

Kept short for `make test` (about 25 s): a few simulated seconds of the star mission in the odometry
room; the whole missions are docs/estimation.md's command."""
import json
import math

import numpy as np
import pytest

from snake_autonomy.runs.batch import BatchRun, RunSpec
from snake_autonomy.sim.feedback import make_feedback
from snake_autonomy.sim.vo_feedback import OdometryCameraSettings, VoFeedback, odometry_anchor
from snake_autonomy.sim.world import SimWorld, WorldSpec
from snake_autonomy.transforms import make_transform, rot_x, rot_y, rot_z


def test_world_step_to_samples_the_imu_at_its_rate_between_driver_steps():
    """Stepped at the driver's 100 Hz, the world still delivers the 200 Hz IMU: one sample on the way
    (imu_between) and one at the step, in time order."""
    world = SimWorld(WorldSpec(seed=0, sensors=("imu",)))
    stamps = []
    for k in range(1, 101):
        out = world.step_to(0.01 * k)
        stamps += [s.t_s for s in out.imu_between] + ([out.imu.t_s] if out.imu is not None else [])
    gaps = np.diff(stamps)
    assert len(stamps) == pytest.approx(200, abs=2)
    assert np.all(gaps > 0) and gaps.mean() == pytest.approx(0.005, rel=0.02)


def test_odometry_anchor_is_level_at_the_cameras_position_and_heading():
    T = make_transform(rot_z(0.7) @ rot_y(0.2) @ rot_x(-0.1), (1.0, -2.0, 0.05))
    A = odometry_anchor(T)
    assert np.allclose(A[:3, 3], T[:3, 3])
    assert np.allclose(A[:3, 2], (0.0, 0.0, 1.0))                       # level
    assert math.atan2(A[1, 0], A[0, 0]) == pytest.approx(0.7, abs=1e-9)   # the camera's heading


def test_vo_refuses_a_bad_camera_setting_and_a_world_without_imu():
    world = SimWorld(WorldSpec(seed=0, sensors=("mocap",)))
    with pytest.raises(ValueError, match="no IMU"):
        VoFeedback(world, world.robot)
    world = SimWorld(WorldSpec(seed=0, feedback="vo"))
    with pytest.raises(ValueError, match=r"width.*got 8"):
        VoFeedback(world, world.robot, camera=OdometryCameraSettings(width=8))
    with pytest.raises(ValueError, match="rate_hz.*got 0"):
        VoFeedback(world, world.robot, camera=OdometryCameraSettings(rate_hz=0))
    with pytest.raises(ValueError, match="feedback vo: needs the world"):
        make_feedback("vo", world.params, world.robot)


def test_vo_batch_run_stays_near_the_truth_and_reports_ape_rpe_and_lost_time(tmp_path):
    """Six simulated seconds of the star mission (the robot at rest while the gyro is calibrated, then
    sidewinding): the gyro calibrated at rest, the estimate drives the mission, stays within 15 cm RMS
    of the plant's camera pose, and the report holds APE, RPE, the lost intervals and their total, the
    frames at 10 Hz and their costs."""
    run = BatchRun(RunSpec(mission="star", seed=0, feedback="vo", time_limit_s=6.0))
    result = run.run()
    m = result.write(tmp_path / "run", plots=False)
    assert json.loads((tmp_path / "run" / "metrics.json").read_text())["vo"] == m["vo"]
    vo, ev = m["vo"], m["vio_evaluation"]
    assert vo["frames"] == pytest.approx((m["sim_time_s"] - run.feedback.start_s) * 10, abs=2)
    assert vo["gyro_calibration"].startswith("calibrated at rest") and vo["waiting"] == 0
    assert vo["tracked"] > 0.7 * vo["frames"]
    assert vo["failed"] == 0 and vo["ms_median"] > 0 and vo["render_ms_median"] > 0
    assert ev["alignment"] == "none"
    assert ev["ape_translation_m"]["rmse"] < 0.15
    assert ev["rpe_translation_m"]["rmse"] < 0.1
    assert ev["lost_s"] >= 0 and ev["loss_intervals"] == len(ev["loss_interval_list"])
    assert vo["lost_s_total"] >= 0
    assert not m["rolled_over"]
    com = result.trajectory
    moved = math.hypot(com["x_true"][-1] - com["x_true"][0], com["y_true"][-1] - com["y_true"][0])
    assert moved > 0.03           # the mission drove the robot on the estimate


def test_vo_blanked_frames_lose_tracking_the_driver_holds_and_tracking_recovers(tmp_path):
    """The lens covered from 2 to 4 s after the odometry's first frame (1.7 to 3.7 s into the motion):
    the odometry reports lost (covariance 9999) and the gate refuses it, so the driver's pose goes
    stale and the mission holds; the frames back, tracking resumes and the report says how long it
    was lost."""
    run = BatchRun(RunSpec(mission="star", seed=0, feedback="vo", time_limit_s=8.0))
    fb = run.feedback
    d = fb.start_s - 0.3                     # the times below count from a first frame at 0.3 s
    fb.blackouts = [(d + 2.0, d + 4.0)]
    statuses = []
    status = fb.status

    def recorded_status(t_s):
        ok, detail = status(t_s)
        statuses.append((t_s, ok, detail))
        return ok, detail
    fb.status = recorded_status
    result = run.run()
    m = result.write(tmp_path / "run", plots=False)
    lost = [s for s in fb.samples if s[3]]
    assert any(d + 2.0 <= s[0] < d + 4.0 for s in lost)
    assert all(s[3] for s in fb.samples if d + 2.15 <= s[0] < d + 4.0)  # every covered frame lost
    assert not any(ok for t, ok, _ in statuses if d + 2.5 <= t < d + 4.0)   # the gate holds the driver
    decisions = zip(result.decisions["t"], result.decisions["pose_stale"])
    assert any(stale for t, stale in decisions if d + 2.5 <= t < d + 4.0)
    assert any(not s[3] for s in fb.samples if s[0] >= d + 4.5)         # tracking resumed
    assert any(ok for t, ok, _ in statuses if t >= d + 5.0)
    assert m["vo"]["lost_s_total"] >= 1.8
    assert m["vio_evaluation"]["lost_s"] >= 1.8
    assert any(i["start"] <= d + 2.2 and i["end"] >= d + 3.9 for i in m["vio_evaluation"]["loss_interval_list"])


def test_vo_batch_run_is_deterministic_per_seed():
    """The same seed twice: the same estimates, losses and true path (renders, noise, RANSAC and the
    smoother repeat; nothing waits on the wall clock)."""
    def run():
        r = BatchRun(RunSpec(mission="star", seed=1, feedback="vo", time_limit_s=4.5))
        result = r.run()
        return np.array([np.r_[s[0], s[1], s[3]] for s in r.feedback.samples]), result.trajectory["x_true"]
    (a, ta), (b, tb) = run(), run()
    assert len(a) > 20 and np.array_equal(a, b) and np.array_equal(ta, tb)
