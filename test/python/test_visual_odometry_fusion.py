"""Visual-inertial fusion (estimation/vio_fusion.py): the visual odometry on the simulator's renders
(test_visual_odometry.py's straight crawl: 1 cm a frame at 10 Hz, i.e. 0.1 m/s) with IMU samples of
sim/imu.py's BMI055-like error model on the true readings of that motion (no rotation, constant
velocity: the specific force is gravity's reaction), at 200 Hz.
"""
import math

import numpy as np
import pytest

from snake_autonomy.estimation.vio_fusion import (FusionParams, VioFusion, level_pose, load_fusion_params,
                                                  local_to_ros, ros_to_local)
from snake_autonomy.estimation.visual_odometry import LOST, LOST_COVARIANCE, OK
from snake_autonomy.perception.camera_model import R_LINK_OPTICAL
from snake_autonomy.sim.imu import DEG, MICRO_G_M_S2, ImuConfig, ImuSensor
from snake_autonomy.transforms import make_transform, rpy_to_matrix

from test_visual_odometry import K, render_path

FRAME_S = 0.1
T_IMU_CAMERA = make_transform(R_LINK_OPTICAL)      # the IMU at camera_link (sim/imu.py)


@pytest.fixture(scope="module")
def straight(root):
    return render_path(root, "straight")


class Run:
    """Feeds frames and the IMU samples before each to a VioFusion; the truth is the straight
    crawl's constant velocity, continued past the rendered frames."""

    def __init__(self, frames, params=None, camera_matrix=None, vo_params=None):
        self.frames = frames
        self.T_world_imu0 = frames[0].T_world_camera @ np.linalg.inv(T_IMU_CAMERA)
        self.velocity = (frames[1].T_world_camera[:3, 3] - frames[0].T_world_camera[:3, 3]) / FRAME_S
        self.f_body = self.T_world_imu0[:3, :3].T @ np.array([0.0, 0.0, 9.80665])
        self.imu = ImuSensor(ImuConfig(), np.random.default_rng(1))
        self.vio = VioFusion(K() if camera_matrix is None else camera_matrix, T_IMU_CAMERA, vo_params, params,
                             initial_imu_pose=self.T_world_imu0)
        self.n_imu = 0

    def frame(self, i, rgb, depth):
        t = FRAME_S * i
        while self.n_imu * 0.005 <= t + 1e-9:
            s = self.imu.measure(self.n_imu * 0.005, np.zeros(3), self.f_body)
            self.vio.add_imu(s.t_s, s.angular_velocity_rad_s, s.linear_acceleration_m_s2)
            self.n_imu += 1
        return self.vio.add_frame(rgb, depth, t)

    def error_m(self, result, i):
        truth = self.frames[0].T_world_camera[:3, 3] + self.velocity * FRAME_S * i
        return float(np.linalg.norm(result.T_world_camera[:3, 3] - truth))


def test_fused_crawl_then_two_seconds_blank_dead_reckons_with_growing_covariance(straight):
    run = Run(straight)
    for i, f in enumerate(straight):
        r = run.frame(i, f.rgb, f.depth_m)
        assert r.state == OK, r.reason
        assert run.error_m(r, i) < 0.005                        # measured: at most 3.0 mm
        assert np.all(np.diag(r.covariance) < 1e-4) and np.array_equal(r.covariance, r.marginal_covariance)
    seen = r
    black, no_depth = np.zeros_like(straight[0].rgb), np.zeros_like(straight[0].depth_m)
    traces = [np.trace(seen.marginal_covariance[:3, :3])]
    n = len(straight)
    for i in range(n, n + 20):                                  # 2 s of blank frames
        r = run.frame(i, black, no_depth)
        assert r.state == LOST and r.reason.startswith("visual odometry lost")
        assert np.array_equal(r.covariance, np.eye(6) * LOST_COVARIANCE)
        traces.append(np.trace(r.marginal_covariance[:3, :3]))
    assert all(b > a for a, b in zip(traces, traces[1:])), traces
    # dead-reckoned, not held: it moved on about as far as the truth (0.2 m); the error (measured
    # 5.0 cm) within 3 marginal stds
    moved = np.linalg.norm(r.T_world_camera[:3, 3] - seen.T_world_camera[:3, 3])
    assert 0.1 < moved < 0.3, moved
    err = run.error_m(r, n + 19)
    assert err < 0.1 and err < 3.0 * math.sqrt(traces[-1]), (err, math.sqrt(traces[-1]))


def test_the_imu_gate_refuses_a_visual_jump(straight):
    """The IMU says 0.1 m/s; a frame 12 cm ahead 0.1 s later is refused, and tracking resumes on
    the next frame consistent with the IMU's motion."""
    run = Run(straight)
    assert run.frame(0, straight[0].rgb, straight[0].depth_m).ok
    r = run.frame(1, straight[12].rgb, straight[12].depth_m)
    assert r.state == LOST and r.reason.startswith("IMU gate") and "gate_m 0.1" in r.reason
    assert r.vo.ok                                              # the visual odometry itself tracked it
    assert np.array_equal(r.covariance, np.eye(6) * LOST_COVARIANCE)
    assert run.error_m(r, 1) < 0.01                             # the IMU's prediction, not the jump
    r = run.frame(2, straight[2].rgb, straight[2].depth_m)
    assert r.state == OK, r.reason
    assert run.error_m(r, 2) < 0.01                             # measured 7.6 mm


def test_covariance_frames_round_trip_and_levelling():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((6, 6))
    cov = A @ A.T
    R = rpy_to_matrix(0.3, -0.2, 1.1)
    assert np.allclose(local_to_ros(ros_to_local(cov, R), R), cov)
    # a level IMU rolled and pitched: levelling on its specific force finds the roll and pitch
    R_world_imu = rpy_to_matrix(math.radians(10), math.radians(-20), 0.0)
    T = level_pose(R_world_imu.T @ np.array([0.0, 0.0, 9.81]))
    assert np.allclose(T[:3, :3] @ (R_world_imu.T @ [0, 0, 1.0]), [0, 0, 1.0])
    assert np.allclose(T[:3, :3], R_world_imu, atol=1e-9)      # zero yaw, as given


def test_config_matches_the_simulated_imu_and_errors_name_the_field(root, tmp_path):
    params = load_fusion_params(root / "config" / "estimation.yaml")
    assert params == FusionParams()
    imu = ImuConfig()
    assert params.gyro_noise_density_rad_s_per_sqrt_hz == pytest.approx(
        imu.gyro_noise_density_deg_s_per_sqrt_hz * DEG, rel=1e-3)
    assert params.accel_noise_density_m_s2_per_sqrt_hz == pytest.approx(
        imu.accel_noise_density_ug_per_sqrt_hz * MICRO_G_M_S2, rel=1e-3)
    assert params.gyro_bias_walk_rad_s_per_sqrt_s == imu.gyro_bias_walk_rad_s_per_sqrt_s
    assert params.accel_bias_walk_m_s2_per_sqrt_s == imu.accel_bias_walk_m_s2_per_sqrt_s
    path = tmp_path / "estimation.yaml"
    for text, message in {"fusion: {lag_s: 0}": "fusion.lag_s: must be a finite number > 0, got 0.0",
                          "fusion: {vo_reset_after_lost: -1}": "fusion.vo_reset_after_lost: must be an integer >= 0, "
                                                               "got -1",
                          "fusion: {gate: 1}": "fusion.gate: unknown key (value 1)"}.items():
        path.write_text(text)
        with pytest.raises(ValueError) as exc:
            load_fusion_params(path)
        assert str(exc.value) == f"{path}: {message}"
