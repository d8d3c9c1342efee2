"""Simulated motion capture and RTAB-Map: rates, frames, noise, drift, tracking loss, seeds."""
import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.estimation.pose_remap import load_camera_calibration
from snake_autonomy.sim.config import Range, SimConfig
from snake_autonomy.sim.mocap import MocapSensor
from snake_autonomy.sim.plant import Plant
from snake_autonomy.sim.pose_sample import LOST_VARIANCE
from snake_autonomy.transforms import quat_to_matrix, rot_z, make_transform
from snake_autonomy.sim.vio import SimulatedVio


@pytest.fixture(scope="module")
def robot(cobra_yaml):
    return _core.RobotModel.from_yaml(cobra_yaml)


@pytest.fixture()
def config(root):
    return SimConfig.from_yaml(root / "config" / "sim.yaml")


@pytest.fixture(scope="module")
def calib(root):
    """T_head^camera from config/camera.yaml, through the pose remapper's own loader."""
    return load_camera_calibration(root / "config" / "camera.yaml").camera_in_head


def _quiet_vio(config):
    v = config.vio
    for key in ("position_noise_m", "rotation_noise_rad", "drift_xy_m_per_sqrt_s",
                "drift_yaw_rad_per_sqrt_s"):
        setattr(v, key, Range(0.0, 0.0))


def test_camera_calibration_file(calib):
    assert calib.shape == (4, 4)
    np.testing.assert_allclose(calib[:3, :3] @ calib[:3, :3].T, np.eye(3), atol=1e-12)


def test_mocap_rate_and_truth(robot, config):
    config.mocap.position_noise_m = Range(0.0, 0.0)
    config.mocap.rotation_noise_rad = Range(0.0, 0.0)
    params = config.draw(seed=1)
    plant = Plant(robot, params, start=(0.5, 0.2, 0.3))
    mocap = MocapSensor(params)
    samples = []
    for k in range(500):               # 1 s of 2 ms steps, polled from t = 0
        plant.step_to(k * 0.002)
        s = mocap.poll(plant)
        if s is not None:
            samples.append(s)
    assert len(samples) == 100
    assert np.allclose(np.diff([s.t_s for s in samples]), 0.01)
    last = samples[-1]
    p, q = plant.frame_pose("base_link")
    np.testing.assert_allclose(last.position_m, p, atol=1e-12)
    np.testing.assert_allclose(quat_to_matrix(*last.quat_xyzw),
                               quat_to_matrix(*q), atol=1e-9)


def test_vio_is_the_camera_pose_through_the_calibration(robot, config, calib):
    _quiet_vio(config)
    params = config.draw(seed=2)
    plant = Plant(robot, params, start=(1.0, -1.0, 1.0))
    vio = SimulatedVio(params, calib)
    plant.step_to(0.2)
    s = vio.measure(plant.time_s, plant.frame_transform("head_link"))
    expected = plant.frame_transform("head_link") @ calib
    np.testing.assert_allclose(s.position_m, expected[:3, 3], atol=1e-12)
    np.testing.assert_allclose(quat_to_matrix(*s.quat_xyzw), expected[:3, :3], atol=1e-9)
    assert not s.lost and s.covariance[0, 0] < 1.0
    # camera_link looks forward and is level: its x axis is the base's x axis
    np.testing.assert_allclose(expected[:3, 0], plant.frame_transform("base_link")[:3, 0],
                               atol=1e-3)


def test_vio_rate_noise_drift(config, calib):
    config.vio.loss_rate_per_min = Range(0.0, 0.0)      # noise and drift only (losses: below)
    params = config.draw(seed=3)
    vio = SimulatedVio(params, calib)
    head = make_transform(rot_z(0.4), (2.0, 1.0, 0.1))
    times = np.arange(0.0, 120.0, 1.0 / 30.0)
    samples = [vio.measure(t, head) for t in times]
    truth = (head @ calib)[:3, 3]
    err = np.array([s.position_m - truth for s in samples])
    early, late = np.abs(err[:30, :2]).mean(), np.abs(err[-30:, :2]).mean()
    assert early < 5 * params.vio_position_noise_m            # white noise only at the start
    assert late > early                                        # the drift has grown
    assert np.abs(err[:, 2]).max() < 6 * params.vio_position_noise_m + 1e-9   # no z drift
    steps = np.diff(err[:, :2], axis=0)
    assert np.abs(steps).max() < 10 * params.vio_position_noise_m   # slow: no jumps


def test_vio_tracking_loss(config, calib):
    config.vio.loss_episodes = [[1.0, 0.5]]
    config.vio.loss_rate_per_min = Range(0.0, 0.0)      # the scheduled episode only
    params = config.draw(seed=4)
    vio = SimulatedVio(params, calib)
    head = make_transform(rot_z(0.0), (0.0, 0.0, 0.1))
    samples = [vio.measure(t, head) for t in np.arange(0.0, 2.0, 1.0 / 30.0)]
    lost = [s for s in samples if s.lost]
    assert all(1.0 <= s.t_s < 1.5 for s in lost) and 14 <= len(lost) <= 16
    for s in lost:
        assert np.all(s.position_m == 0) and np.all(s.quat_xyzw == 0)
        assert np.all(np.diag(s.covariance) == LOST_VARIANCE)
    assert not samples[-1].lost


def test_vio_random_losses_per_seed(config, calib):
    config.vio.loss_rate_per_min = Range(6.0, 6.0)     # one every 10 s on average
    head = make_transform(translation=(0.0, 0.0, 0.1))

    def lost_times(seed):
        vio = SimulatedVio(config.draw(seed=seed), calib)
        return [s.t_s for s in (vio.measure(t, head) for t in np.arange(0.0, 120.0, 1 / 30.0))
                if s.lost]

    a, b, c = lost_times(5), lost_times(5), lost_times(6)
    assert a == b and a != c
    assert len(a) > 0


def test_sensors_deterministic_per_seed(config, calib):
    head = make_transform(rot_z(0.2), (1.0, 2.0, 0.1))

    def run(seed):
        params = config.draw(seed=seed)
        vio, mocap = SimulatedVio(params, calib), MocapSensor(params)
        return np.array([np.r_[vio.measure(t, head).position_m, mocap.measure(t, head).position_m]
                         for t in np.arange(0.0, 3.0, 1 / 30.0)])

    assert np.array_equal(run(9), run(9))
    assert not np.array_equal(run(9), run(10))
