"""The rectilinear gait of Chang et al. (eq. 2) on a chain of alternating pitch and yaw joints: a
Python reference that drives the plant's joint targets directly.

    z(s, t) = A sin(2 pi (f t + direction * s / lambda))     vertical travelling wave
    the average body in the ground plane: an arc of constant curvature kappa

s is the arc length from the front of the robot (base_link's origin) towards the tail; joint i sits
at s_i = H + (i - 1) L. Discretised on the joint spacing:
- pitch joints: the vertical curve through the pitch joints' heights z(s_k) is a polyline; each
  pitch joint's angle is the change of the polyline's slope across it (the first segment runs from
  the front, s = 0, the last to the tail end);
- yaw joints: kappa times the spacing of the yaw joints (the tangent turns by kappa per metre).
pitch_sign and yaw_sign map these angles to the joints' q (the thesis's eq. 3.4 axes): yaw_sign is
chosen so that kappa > 0 bends the body to the left (CCW path), measured on the plant.

Driving goes through the driver now (config/gaits.yaml `rectilinear`, derived from this
discretisation, with the C++ `curvature` steering law; runs/gait_driver.py): this module stays the
reference the gait map and the tests check against (navigation drives the driver's gait only).
"""
import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RectilinearGait:
    amplitude_m: float = 0.02          # A
    wavelength_m: float = 1.0          # lambda
    frequency_hz: float = 0.4          # f (paper: 4 cycles in 10 s)
    direction: float = 1.0             # +1: wave phase advances towards the tail (see module doc)
    pitch_sign: float = 1.0
    yaw_sign: float = 1.0

    def joint_angles(self, robot, t_s: float, kappa_per_m: float = 0.0, yaw_kappas=None) -> np.ndarray:
        """yaw_kappas: one curvature per yaw joint, head to tail (follow_the_leader.py); None: every
        yaw joint at kappa_per_m."""
        axes = list(robot.axes)
        H, L = robot.head_length_m, robot.link_length_m
        n = len(axes)
        s_joint = H + L * np.arange(n)
        tail = H + L * n
        q = np.zeros(n)
        pitch = [i for i, a in enumerate(axes) if a == "pitch"]
        yaw = [i for i, a in enumerate(axes) if a == "yaw"]
        if pitch:
            s = np.concatenate([[0.0], s_joint[pitch], [tail]])
            z = self.amplitude_m * np.sin(2 * math.pi * (self.frequency_hz * t_s
                                                         + self.direction * s / self.wavelength_m))
            slope = np.arctan2(np.diff(z), np.diff(s))
            q[pitch] = self.pitch_sign * np.diff(slope)
        if len(yaw) > 1:
            spacing = float(np.mean(np.diff(s_joint[yaw])))
        else:
            spacing = 2 * L
        q[yaw] = self.yaw_sign * (kappa_per_m if yaw_kappas is None else np.asarray(yaw_kappas, float)) * spacing
        return q
