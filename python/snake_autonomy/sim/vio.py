"""A simulated RTAB-Map: visual-inertial odometry of the head camera (thesis 3.3, 4.1).

Each sample (30 Hz) is the camera's pose, T_world^camera = T_world^head . T_head^camera (the
calibration of config/camera.yaml, camera_in_head, loaded by the pose remapper's
snake_autonomy.estimation.pose_remap.load_camera_calibration: one reader for the one file), as
the odometry would report it:

- white noise on position (per axis) and orientation (a small rotation in the camera frame);
- slow drift: the odometry frame wanders from the world frame by a random walk in x, y and yaw
  (m and rad per sqrt(s)). The yaw drift turns about the camera's first position, so the error
  grows with the distance travelled, not with the distance from the world origin;
- tracking-loss episodes, scheduled ([start_s, duration_s] in the config) or random (Poisson, rate
  per minute, durations drawn from a range): RTAB-Map then publishes a null pose (position and
  quaternion all zeros) with covariance 9999 on the diagonal. The drift keeps walking during an
  episode, so tracking comes back with a small jump, as it does on the robot.

The output frame is the world frame plus drift (the odometry frame aligned with the world at the
start): what eq. 3.1 of the thesis takes as T_camera^world. Every random number comes from the
seed's "vio" streams, so a seed gives the same samples whatever else runs.
"""
from typing import List, Optional, Tuple

import numpy as np

from .config import SimParams
from .pose_sample import PoseSample, diagonal_covariance
from .sensor_clock import SensorClock
from ..transforms import matrix_to_quat, rot_z, rotvec_to_matrix, make_transform


class SimulatedVio:
    def __init__(self, params: SimParams, head_t_camera: np.ndarray, frame: str = "camera"):
        cfg = params.config.vio
        self.frame = frame
        self.head_t_camera = np.asarray(head_t_camera, float)
        self.clock = SensorClock(cfg.rate_hz)
        self.position_std_m = params.vio_position_noise_m
        self.rotation_std_rad = params.vio_rotation_noise_rad
        self.drift_xy = params.vio_drift_xy_m_per_sqrt_s
        self.drift_yaw = params.vio_drift_yaw_rad_per_sqrt_s
        self.loss_rate_per_s = params.vio_loss_rate_per_min / 60.0
        self.loss_duration = cfg.loss_duration_s
        self.scheduled_losses: List[Tuple[float, float]] = sorted(
            (float(s), float(s) + float(d)) for s, d in cfg.loss_episodes)
        self._noise_rng = params.rng("vio.noise")
        self._drift_rng = params.rng("vio.drift")
        self._loss_rng = params.rng("vio.loss")
        self._cov = diagonal_covariance(self.position_std_m, self.rotation_std_rad)
        self._drift = np.zeros(3)           # dx, dy, dyaw of the odometry frame
        self._pivot = None                  # camera's first position (the yaw drift's centre)
        self._last_t = None
        self._random_loss = self._draw_random_loss(0.0)

    # ---- sampling ------------------------------------------------------------------------------
    def measure(self, t_s: float, world_t_head: np.ndarray) -> PoseSample:
        """The odometry sample at t_s for the true head pose (4x4)."""
        self.clock.tick(t_s)
        world_t_camera = world_t_head @ self.head_t_camera
        if self._pivot is None:
            self._pivot = world_t_camera[:3, 3].copy()
        self._walk(t_s)
        noise = self._noise_rng.normal(size=6)      # drawn even when lost: streams stay aligned
        if self.lost(t_s):
            return PoseSample.lost_sample(t_s, self.frame)
        estimate = self.drift_transform() @ world_t_camera
        position = estimate[:3, 3] + self.position_std_m * noise[:3]
        rotation = estimate[:3, :3] @ rotvec_to_matrix(self.rotation_std_rad * noise[3:])
        return PoseSample(t_s, self.frame, position, matrix_to_quat(rotation),
                          self._cov.copy())

    def poll(self, plant) -> Optional[PoseSample]:
        if not self.clock.due(plant.time_s):
            return None
        return self.measure(plant.time_s, plant.frame_transform("head_link"))

    # ---- drift and losses ----------------------------------------------------------------------
    def drift_transform(self) -> np.ndarray:
        """4x4 map from the world to the drifted odometry frame (identity at the start)."""
        pivot = np.zeros(3) if self._pivot is None else self._pivot
        dx, dy, dyaw = self._drift
        about_pivot = (make_transform(translation=pivot) @ make_transform(rot_z(dyaw))
                       @ make_transform(translation=-pivot))
        return make_transform(translation=(dx, dy, 0.0)) @ about_pivot

    def lost(self, t_s: float) -> bool:
        if any(start <= t_s < end for start, end in self.scheduled_losses):
            return True
        while self._random_loss is not None and t_s >= self._random_loss[1]:
            self._random_loss = self._draw_random_loss(self._random_loss[1])
        return self._random_loss is not None and self._random_loss[0] <= t_s

    def _walk(self, t_s: float) -> None:
        if self._last_t is not None and t_s > self._last_t:
            root_dt = np.sqrt(t_s - self._last_t)
            steps = self._drift_rng.normal(size=3) * root_dt
            self._drift += steps * (self.drift_xy, self.drift_xy, self.drift_yaw)
        self._last_t = t_s

    def _draw_random_loss(self, after_s: float):
        """The next random episode (start_s, end_s) after after_s, or None when the rate is 0."""
        if self.loss_rate_per_s <= 0:
            return None
        start = after_s + self._loss_rng.exponential(1.0 / self.loss_rate_per_s)
        return start, start + float(self.loss_duration.draw(self._loss_rng))
