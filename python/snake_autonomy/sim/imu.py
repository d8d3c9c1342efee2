"""The D435i's IMU (a Bosch BMI055) at the head camera: MuJoCo's gyro and accelerometer at the
camera_link site of the plant (sim/mjcf.py, Plant(imu_in_head=...)) plus a BMI055-like error model.

    imu = ImuSensor(config.imu, params.rng("imu"), step_s=plant.dt_s)
    sample = imu.poll(plant)        # an ImuSample when one fell due at plant.time_s, else None
    sample = imu.measure(t_s, gyro_rad_s, accel_m_s2)    # the error model alone, on true readings

Samples fall on the rate's grid of simulated time, each taken at the physics step nearest its grid
point: the plant's time moves in whole steps (2 ms), and a 200 Hz grid is not a whole number of
them, so the spacing alternates (4 and 6 ms at 200 Hz) around the rate's period. A sample's time
is that of the state MuJoCo's sensors read (Plant.imu_truth: one physics step back).

The accelerometer's sample is the mean of the specific force over every physics step since the
previous sample (Plant.imu_accel_mean), as the BMI055's digital low-pass filter averages before it
decimates: an instant sample would alias the head's contact jolts (a few ms long, tens of m/s^2) into
the 200 Hz samples. The gyro's sample is the instant reading (the body's rate changes smoothly).

What it does to the true readings (config/sim.yaml imu:, ImuConfig), per axis and sample:
- white noise of the datasheet's noise density over the sample's bandwidth: std = density x
  sqrt(rate_hz / 2) (the sensor's low-pass filter keeps the noise below the Nyquist frequency);
- a bias that walks: per sample a step of walk x sqrt(1 / rate_hz). The gyro's starts at its
  zero-rate offset, drawn once per sensor (normal, std gyro_offset_deg_s per axis) from a child of
  the generator given (Generator.spawn: the noise sequence is the same whatever the offset), as a
  real gyro's differs from one power-up to the next; the estimator calibrates it at rest
  (estimation/rest_calibration.py). The accelerometer's starts at zero (its zero-g offset is not
  modelled).
Frame and units as REP 145 wants them: the sensor frame (camera_link, x forward, y left, z up),
angular velocity in rad/s, linear acceleration in m/s^2 including gravity (at rest: +9.81 along
the frame's up). Every random number comes from the generator given (the seed's "imu" stream).
"""
import math
from dataclasses import dataclass
from typing import List, Optional

import numpy as np

from .sensor_clock import SensorClock

DEG = math.pi / 180.0
MICRO_G_M_S2 = 9.80665e-6


@dataclass
class ImuConfig:
    # One rate for both: realsense-ros publishes the BMI055's gyro (200 or 400 Hz) and accelerometer
    # (63 or 250 Hz) as one sensor_msgs/Imu at the gyro's rate (unite_imu_method), and sim_node polls
    # its sensors at 200 Hz: a 250 Hz accelerometer would alias onto that poll's grid.
    rate_hz: float = 200.0
    gyro_noise_density_deg_s_per_sqrt_hz: float = 0.014     # BMI055 datasheet, gyroscope noise density
    accel_noise_density_ug_per_sqrt_hz: float = 150.0       # BMI055 datasheet, accelerometer (2 g range)
    # Bias random walks: the datasheet gives none. ESTIMATES of the order Allan-variance calibrations
    # of MEMS IMUs of this class report (rad/s and m/s^2 per sqrt(s), i.e. per s x sqrt(Hz)).
    gyro_bias_walk_rad_s_per_sqrt_s: float = 2.0e-5
    accel_bias_walk_m_s2_per_sqrt_s: float = 4.0e-4
    # the gyro's zero-rate offset at power-up: std of a normal draw per axis (deg/s; 0: none, a gyro
    # calibrated beforehand): the BMI055 datasheet's +-1 deg/s typical taken as 2 sigma, as config/sim.yaml
    gyro_offset_deg_s: float = 0.5

    def problems(self, prefix: str = "imu") -> List[str]:
        """Every invalid value, each naming its key."""
        out = []
        for key in ("rate_hz", "gyro_noise_density_deg_s_per_sqrt_hz", "accel_noise_density_ug_per_sqrt_hz",
                    "gyro_bias_walk_rad_s_per_sqrt_s", "accel_bias_walk_m_s2_per_sqrt_s", "gyro_offset_deg_s"):
            v, need = getattr(self, key), ("> 0" if key == "rate_hz" else ">= 0")
            number = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            if not number or v < 0 or (key == "rate_hz" and v == 0):
                out.append(f"{prefix}.{key}: must be a finite number {need}, got {v!r}")
        return out

    @property
    def gyro_std_rad_s(self) -> float:
        """White-noise std of one gyro sample (rad/s)."""
        return self.gyro_noise_density_deg_s_per_sqrt_hz * DEG * math.sqrt(self.rate_hz / 2.0)

    @property
    def accel_std_m_s2(self) -> float:
        """White-noise std of one accelerometer sample (m/s^2)."""
        return self.accel_noise_density_ug_per_sqrt_hz * MICRO_G_M_S2 * math.sqrt(self.rate_hz / 2.0)


@dataclass
class ImuSample:
    t_s: float
    angular_velocity_rad_s: np.ndarray      # (3,) in the sensor frame
    linear_acceleration_m_s2: np.ndarray    # (3,) specific force in the sensor frame (gravity included)
    gyro_std_rad_s: float                   # white-noise std per axis (the message's covariances)
    accel_std_m_s2: float


class ImuSensor:
    """True gyro and specific force -> BMI055-like samples (see the module's docstring)."""

    def __init__(self, config: ImuConfig, rng: np.random.Generator, step_s: float = 0.0):
        """step_s: the plant's physics step (a grid point is due from half a step before it)."""
        problems = config.problems()
        if problems:
            raise ValueError("imu: " + "; ".join(problems))
        self.config, self.rng = config, rng
        self.clock = SensorClock(config.rate_hz)
        self.half_step_s = 0.5 * float(step_s)
        self.gyro_std, self.accel_std = config.gyro_std_rad_s, config.accel_std_m_s2
        self._walk_step = math.sqrt(1.0 / config.rate_hz) * np.array(
            [config.gyro_bias_walk_rad_s_per_sqrt_s] * 3 + [config.accel_bias_walk_m_s2_per_sqrt_s] * 3)
        # the zero-rate offset from a child stream: the parent's draws (the noise) stay as they were
        self.gyro_offset_rad_s = rng.spawn(1)[0].standard_normal(3) * config.gyro_offset_deg_s * DEG
        self.bias = np.r_[self.gyro_offset_rad_s, np.zeros(3)]   # gyro (rad/s), accelerometer (m/s^2)

    def poll(self, plant) -> Optional[ImuSample]:
        """The plant's IMU sample when one fell due at its present time (the grid point within half a
        physics step), else None."""
        if not self.clock.due(plant.time_s + self.half_step_s):
            return None
        self.clock.tick(plant.time_s + self.half_step_s)
        t_s, gyro, _ = plant.imu_truth()
        return self.measure(t_s, gyro, plant.imu_accel_mean())

    def step_plant_to(self, plant, t_s: float) -> List[ImuSample]:
        """The plant to t_s, stopping at each of this IMU's sample times before it (its rate against a
        slower caller's): the samples taken on the way. The sample at t_s itself is poll()'s."""
        samples, half = [], self.half_step_s
        while self.clock.next_s + half < t_s - 1e-9:
            # the physics step nearest the grid point (poll: due from half a step before)
            plant.step_to(math.ceil((self.clock.next_s - half) / plant.dt_s - 1e-9) * plant.dt_s)
            s = self.poll(plant)
            if s is None:
                break
            samples.append(s)
        plant.step_to(t_s)
        return samples

    def measure(self, t_s: float, gyro_rad_s, accel_m_s2) -> ImuSample:
        """A sample at t_s of the true angular velocity and specific force (sensor frame)."""
        draws = self.rng.standard_normal(12)    # white noise, then the bias's step: a fixed stream
        self.bias += self._walk_step * draws[6:]
        white = draws[:6] * np.array([self.gyro_std] * 3 + [self.accel_std] * 3)
        gyro = np.asarray(gyro_rad_s, float) + self.bias[:3] + white[:3]
        accel = np.asarray(accel_m_s2, float) + self.bias[3:] + white[3:]
        return ImuSample(float(t_s), gyro, accel, self.gyro_std, self.accel_std)
