"""Open-loop serpenoid joint patterns: the plant's check before (and beside) the CPG.

    q_i(t) = a_i sin(omega t + phi_i) + b_i

with one amplitude per axis, phi_i = i * lag + (offset for pitch joints), i = 0 for joint 1. These
are the steady states the CPG converges to (thesis 3.5.2): yaw amplitude about 45 deg, pitch about
15 deg, the vertical wave 90 deg from the horizontal one. Steering modulates the yaw amplitudes
with the robot's steering weights (thesis eq. 3.26, Algorithm 1's MODIFYAMPLITUDES):
a_yaw_k += w_k * delta, clamped to +-amplitude_limit
(Algorithm 1's clamp, as ran on the robot, not section 3.6.3's clip).

The values here are this module's own choices for the open-loop check (see SIDEWINDING and
TURN_IN_PLACE); the gait library (config/gaits.yaml, _core.GaitLibrary) is the reference once
it is on main.
"""
from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class Serpenoid:
    frequency_hz: float = 0.7
    yaw_amplitude_rad: float = np.radians(45.0)
    pitch_amplitude_rad: float = np.radians(15.0)
    lag_rad: float = np.radians(30.0)           # phase step from joint i to joint i + 1
    pitch_offset_rad: float = np.radians(90.0)  # vertical wave ahead of the horizontal one
    pitch_lag_rad: float = None                 # the vertical wave's own lag (None: lag_rad)
    delta_rad: float = 0.0                      # steering (amplitude modulation)

    def with_delta(self, delta_rad: float) -> "Serpenoid":
        return replace(self, delta_rad=delta_rad)

    def mirrored(self) -> "Serpenoid":
        """The same gait turning (or travelling) the other way: the vertical wave reversed."""
        return replace(self, pitch_offset_rad=self.pitch_offset_rad + np.pi)

    def amplitudes_rad(self, robot) -> np.ndarray:
        axes = list(robot.axes)
        amp = np.array([self.yaw_amplitude_rad if a == "yaw" else self.pitch_amplitude_rad
                        for a in axes])
        if self.delta_rad:
            yaw = [i for i, a in enumerate(axes) if a == "yaw"]
            weights = np.asarray(robot.steering_weights, float)
            limit = robot.amplitude_limit_rad
            amp[yaw] = np.clip(amp[yaw] + weights * self.delta_rad, -limit, limit)
        return amp

    def phases_rad(self, robot) -> np.ndarray:
        axes = list(robot.axes)
        pitch_lag = self.lag_rad if self.pitch_lag_rad is None else self.pitch_lag_rad
        return np.array([i * pitch_lag + self.pitch_offset_rad if a == "pitch" else i * self.lag_rad
                         for i, a in enumerate(axes)])

    def joint_angles(self, robot, t_s: float) -> np.ndarray:
        omega = 2 * np.pi * self.frequency_hz
        return self.amplitudes_rad(robot) * np.sin(omega * t_s + self.phases_rad(robot))


# The open-loop check's sidewinding: 0.7 Hz, 45/15 deg, 90 deg between the waves, 30 deg per
# joint (60 deg between consecutive yaw joints: about one wavelength over the body).
SIDEWINDING = Serpenoid()

# Turn in place: the vertical wave travels along the body the other way from the horizontal one,
# so head and tail push sideways in opposite directions. Chosen by a sweep of amplitudes, lags and
# offsets on the nominal plant for a fast turn with little translation (about 50 deg/s clockwise
# at under 0.05 m/s); mirror it to turn the other way.
TURN_IN_PLACE = Serpenoid(yaw_amplitude_rad=np.radians(50.0), pitch_amplitude_rad=np.radians(25.0),
                          pitch_lag_rad=-np.radians(30.0), pitch_offset_rad=np.radians(75.0))
