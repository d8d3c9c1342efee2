"""Motion capture of the tracked base (OptiTrack in the thesis): base_link's pose at 100 Hz with
small white noise. Ground truth for evaluation, and the 'mocap' feedback source.

    mocap = MocapSensor(params)
    sample = mocap.poll(plant)     # a PoseSample when one is due at plant.time_s, else None
"""
from typing import Optional

import numpy as np

from .config import SimParams
from .pose_sample import PoseSample, diagonal_covariance
from .sensor_clock import SensorClock
from ..transforms import matrix_to_quat, rotvec_to_matrix


class MocapSensor:
    def __init__(self, params: SimParams, frame: str = "base_link"):
        self.frame = frame
        self.clock = SensorClock(params.config.mocap.rate_hz)
        self.position_std_m = params.mocap_position_noise_m
        self.rotation_std_rad = params.mocap_rotation_noise_rad
        self._rng = params.rng("mocap")
        self._cov = diagonal_covariance(self.position_std_m, self.rotation_std_rad)

    def measure(self, t_s: float, world_t_frame: np.ndarray) -> PoseSample:
        """A sample of the true 4x4 pose world_t_frame taken at t_s (noise added)."""
        self.clock.tick(t_s)
        noise = self._rng.normal(size=6)
        position = world_t_frame[:3, 3] + self.position_std_m * noise[:3]
        rotation = world_t_frame[:3, :3] @ rotvec_to_matrix(self.rotation_std_rad * noise[3:])
        return PoseSample(t_s, self.frame, position, matrix_to_quat(rotation),
                          self._cov.copy())

    def poll(self, plant) -> Optional[PoseSample]:
        if not self.clock.due(plant.time_s):
            return None
        return self.measure(plant.time_s, plant.frame_transform(self.frame))
