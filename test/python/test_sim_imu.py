"""The head camera's IMU (sim/imu.py; MuJoCo's gyro and accelerometer at the camera_link site of
sim/mjcf.py): what sim_node publishes on camera/imu. At rest it reads gravity and no rotation but its
zero-rate offset (drawn per seed), a positive yaw rate (REP 103: counter-clockwise seen from above)
reads positive about the sensor's up axis, and the white noise is the configured density over the Nyquist band."""
import math

import mujoco
import numpy as np
import pytest

from snake_autonomy.estimation import load_camera_calibration
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.imu import ImuConfig, ImuSensor
from snake_autonomy.sim.world import SimWorld, WorldSpec

G = 9.81


def _world(heading_deg: float = 0.0) -> SimWorld:
    return SimWorld(WorldSpec(seed=0, start=(0.0, 0.0, heading_deg), sensors=("mocap", "imu")))


def _world_R_sensor(world: SimWorld) -> np.ndarray:
    """camera_link's rotation in the world: the site's, checked against head_link . camera.yaml."""
    camera_in_head = load_camera_calibration(world.config.calibration_path()).camera_in_head
    sid = mujoco.mj_name2id(world.plant.model, mujoco.mjtObj.mjOBJ_SITE, "camera_link")
    R = world.plant.data.site_xmat[sid].reshape(3, 3)
    np.testing.assert_allclose(R, (world.plant.frame_transform("head_link") @ camera_in_head)[:3, :3], atol=1e-9)
    return R


def test_at_rest_the_accelerometer_reads_gravity_up_and_the_gyro_nothing():
    world = _world(30.0)
    world.step_to(1.0)                       # dropped from 1 mm: settled
    samples = [s for s in (world.step_to(1.0 + k * world.plant.dt_s).imu for k in range(1, 1001)) if s]
    assert len(samples) == pytest.approx(2.0 * world.config.imu.rate_hz, abs=1)   # 200 Hz over 2 s
    assert world.plant.imu_truth()[0] == pytest.approx(world.plant.time_s - world.plant.dt_s)   # read before the step
    gaps = np.diff([s.t_s for s in samples])                 # each at the physics step nearest its grid point
    assert gaps.mean() == pytest.approx(1.0 / world.config.imu.rate_hz, rel=0.01)
    assert gaps.min() >= 1.0 / world.config.imu.rate_hz - world.plant.dt_s - 1e-9
    gyro = np.array([s.angular_velocity_rad_s for s in samples])
    accel = np.array([s.linear_acceleration_m_s2 for s in samples])
    up_in_sensor = _world_R_sensor(world).T @ np.array([0.0, 0.0, 1.0])
    assert up_in_sensor[2] > 0.99                            # camera_link lies level: z up
    np.testing.assert_allclose(accel.mean(axis=0), G * up_in_sensor, atol=0.02)
    assert np.linalg.norm(accel.mean(axis=0)) == pytest.approx(G, abs=0.02)
    cfg = world.config.imu
    offset = world.imu.gyro_offset_rad_s                     # the seed's zero-rate offset, BMI055-sized
    assert 0 < np.abs(offset).max() < 3 * cfg.gyro_offset_deg_s * math.pi / 180
    assert np.all(np.abs(gyro.mean(axis=0) - offset) < 4 * cfg.gyro_std_rad_s / math.sqrt(len(samples)) + 1e-4)
    np.testing.assert_allclose(gyro.std(axis=0), cfg.gyro_std_rad_s, rtol=0.2)
    np.testing.assert_allclose(accel.std(axis=0), cfg.accel_std_m_s2, rtol=0.2)


@pytest.mark.parametrize("yaw_rate", [0.5, -0.5])
def test_a_yawing_body_reads_the_yaw_rate_with_its_sign_about_the_sensors_up_axis(yaw_rate):
    world = _world(-60.0)
    data = world.plant.data
    data.qvel[:] = 0.0
    data.qvel[3:6] = (0.0, 0.0, yaw_rate)    # free joint: base_link's angular velocity in its own frame
    mujoco.mj_forward(world.plant.model, data)
    t_s, gyro, accel = world.plant.imu_truth()
    assert t_s == world.plant.time_s == 0.0                  # a forward pass at the present state
    R = _world_R_sensor(world)
    base_z = world.plant.frame_transform("base_link")[:3, 2]
    np.testing.assert_allclose(R @ gyro, yaw_rate * base_z, atol=1e-9)   # the body's rate, in the world
    assert gyro[2] == pytest.approx(yaw_rate, abs=1e-3)      # level sensor: + about z is counter-clockwise
    sample = ImuSensor(world.config.imu, np.random.default_rng(0)).measure(0.0, gyro, accel)
    assert math.copysign(1.0, sample.angular_velocity_rad_s[2]) == math.copysign(1.0, yaw_rate)


@pytest.mark.parametrize("rate_hz", [200.0, 400.0])
def test_white_noise_std_is_the_density_over_the_nyquist_band(rate_hz):
    cfg = ImuConfig(rate_hz=rate_hz, gyro_bias_walk_rad_s_per_sqrt_s=0.0, accel_bias_walk_m_s2_per_sqrt_s=0.0,
                    gyro_offset_deg_s=0.0)
    imu = ImuSensor(cfg, np.random.default_rng(1))
    out = [imu.measure(k / rate_hz, np.zeros(3), np.array([0.0, 0.0, G])) for k in range(20000)]
    gyro = np.array([s.angular_velocity_rad_s for s in out])
    accel = np.array([s.linear_acceleration_m_s2 for s in out])
    gyro_std = 0.014 * math.pi / 180 * math.sqrt(rate_hz / 2)       # BMI055: 0.014 deg/s/sqrt(Hz)
    accel_std = 150e-6 * 9.80665 * math.sqrt(rate_hz / 2)           # BMI055: 150 ug/sqrt(Hz)
    np.testing.assert_allclose(gyro.std(axis=0), gyro_std, rtol=0.2)
    np.testing.assert_allclose(accel.std(axis=0), accel_std, rtol=0.2)
    assert out[0].gyro_std_rad_s == pytest.approx(gyro_std) and out[0].accel_std_m_s2 == pytest.approx(accel_std)


def test_the_bias_walks_as_configured():
    cfg = ImuConfig(gyro_noise_density_deg_s_per_sqrt_hz=0.0, accel_noise_density_ug_per_sqrt_hz=0.0,
                    gyro_offset_deg_s=0.0)
    ends = []
    for seed in range(300):
        imu = ImuSensor(cfg, np.random.default_rng(seed))
        for k in range(400):                 # 2 s at 200 Hz
            s = imu.measure(k / cfg.rate_hz, np.zeros(3), np.zeros(3))
        ends.append(np.concatenate([s.angular_velocity_rad_s, s.linear_acceleration_m_s2]))
    std = np.array(ends).std(axis=0)
    np.testing.assert_allclose(std[:3], cfg.gyro_bias_walk_rad_s_per_sqrt_s * math.sqrt(2.0), rtol=0.2)
    np.testing.assert_allclose(std[3:], cfg.accel_bias_walk_m_s2_per_sqrt_s * math.sqrt(2.0), rtol=0.2)


def test_the_gyro_offset_is_drawn_per_seed_and_leaves_the_noise_sequence_as_it_was():
    """The zero-rate offset: the same seed gives the same offset, other seeds others, spread as configured
    (std per axis); the white noise and the walk are the same draws with or without it."""
    cfg = ImuConfig(gyro_offset_deg_s=0.5)
    offsets = np.array([ImuSensor(cfg, np.random.default_rng([seed, 7])).gyro_offset_rad_s for seed in range(400)])
    again = ImuSensor(cfg, np.random.default_rng([3, 7])).gyro_offset_rad_s
    assert np.array_equal(again, offsets[3]) and not np.array_equal(offsets[3], offsets[4])
    np.testing.assert_allclose(offsets.std(axis=0), math.radians(0.5), rtol=0.15)
    with_offset = ImuSensor(cfg, np.random.default_rng(5))
    without = ImuSensor(ImuConfig(gyro_offset_deg_s=0.0), np.random.default_rng(5))
    assert np.array_equal(without.gyro_offset_rad_s, np.zeros(3))
    for k in range(50):
        a = with_offset.measure(0.005 * k, np.zeros(3), np.zeros(3))
        b = without.measure(0.005 * k, np.zeros(3), np.zeros(3))
        np.testing.assert_allclose(a.angular_velocity_rad_s - b.angular_velocity_rad_s, with_offset.gyro_offset_rad_s,
                                   atol=1e-15)
        assert np.array_equal(a.linear_acceleration_m_s2, b.linear_acceleration_m_s2)
    for bad in (-0.1, math.nan, "1"):
        with pytest.raises(ValueError, match=f"imu.gyro_offset_deg_s: must be a finite number >= 0, got {bad!r}"):
            ImuSensor(ImuConfig(gyro_offset_deg_s=bad), np.random.default_rng(0))


def test_without_the_imu_the_model_has_no_sensors():
    world = SimWorld(WorldSpec(seed=0, sensors=("mocap",)))
    assert world.plant.model.nsensor == 0 and world.imu is None and world.step_to(0.01).imu is None
    with pytest.raises(ValueError, match="no IMU"):
        world.plant.imu_truth()


@pytest.mark.parametrize("raw, message", [
    ({"rate_hz": 0}, r"imu\.rate_hz: must be a finite number > 0, got 0"),
    ({"gyro_noise_density_deg_s_per_sqrt_hz": -0.01}, r"imu\.gyro_noise_density_deg_s_per_sqrt_hz: must be a "
                                                       r"finite number >= 0, got -0\.01"),
    ({"accel_bias_walk_m_s2_per_sqrt_s": "x"}, r"imu\.accel_bias_walk_m_s2_per_sqrt_s: expected float, got 'x'"),
    ({"bogus": 1}, r"imu\.bogus: unknown key"),
])
def test_bad_imu_values_are_refused_naming_the_key(raw, message):
    with pytest.raises(ValueError, match=message):
        SimConfig.from_dict({"imu": raw})


def test_the_accelerometer_sample_is_the_mean_over_its_period_and_the_gyro_the_instant_reading():
    """As the BMI055's digital filter averages before it decimates: a contact jolt of one physics step
    enters its sample weighted by its share of the period, not whole or not at all."""
    world = _world()
    plant = world.plant
    quiet = ImuConfig(gyro_noise_density_deg_s_per_sqrt_hz=0.0, accel_noise_density_ug_per_sqrt_hz=0.0,
                      gyro_bias_walk_rad_s_per_sqrt_s=0.0, accel_bias_walk_m_s2_per_sqrt_s=0.0,
                      gyro_offset_deg_s=0.0)
    imu = ImuSensor(quiet, np.random.default_rng(0), step_s=plant.dt_s)
    a = int(plant.model.sensor_adr[mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_SENSOR, "imu_accel")])
    assert not plant.disturbances.items     # the jolts below are the only pushes
    readings, checked, off_instant = [], 0, 0.0
    imu.poll(plant)                          # t = 0: the forward pass's reading, and the sum starts
    for k in range(1, 200):                  # 0.4 s of 2 ms steps, a jolt on the head every 10th
        if k % 10 == 0:
            plant.data.xfrc_applied[plant._body_id("base_link"), 2] = 200.0
        plant.step_to(k * plant.dt_s)
        plant.data.xfrc_applied[:] = 0.0
        readings.append(plant.data.sensordata[a:a + 3].copy())
        s = imu.poll(plant)
        if s is None:
            continue
        # mj_step's sensors read the state before it integrates: the readings summed are those
        # MuJoCo computed in each step taken since the previous sample
        np.testing.assert_allclose(s.linear_acceleration_m_s2, np.mean(readings, axis=0), atol=1e-9)
        np.testing.assert_allclose(s.angular_velocity_rad_s, plant.imu_truth()[1], atol=1e-12)
        off_instant = max(off_instant, float(np.abs(s.linear_acceleration_m_s2 - readings[-1]).max()))
        readings, checked = [], checked + 1
    assert checked == pytest.approx(0.4 * quiet.rate_hz, abs=2)
    assert off_instant > 1.0                 # the jolts: the mean is not the last step's reading
