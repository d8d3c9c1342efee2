"""The gyro's zero-rate offset measured at rest, before the visual-inertial fusion's first frame, ROS-free.

    cal = calibrate_gyro_at_rest(gyro_rad_s, accel_m_s2, span_s, settings)
    cal.bias_rad_s, cal.sigma_rad_s     # the fusion's gyro bias prior: mean and std per axis
    cal.calibrated, cal.detail          # whether the window was at rest, and what was measured

A MEMS gyro's zero-rate offset changes from one power-up to the next (the D435i's BMI055: +-1 deg/s
per axis, typical), far beyond what the heading can afford (docs/vo_error_sources.md). As the static
initialisers of OpenVINS and VINS-Mono's IMU-only start do, the robot is held still for a window and
the mean angular rate over it is the bias: the fusion's bias prior is centred there. Its std is the
configured one or, when larger, the window mean's own standard error (the sample std over sqrt(n)).

A window is at rest when the gyro's std about its mean is within max_gyro_std_rad_s on every axis,
the mean rate's norm within max_rate_rad_s, and the mean specific force's norm within
max_accel_m_s2 of gravity. A window that moved, or one shorter than window_s, is not calibrated: the
prior is zero-mean with the uncalibrated std (a few datasheet offsets), and detail says why with
the measured figures. window_s 0: no calibration at rest, the prior zero-mean with the calibrated std
(a gyro calibrated beforehand, its offsets removed upstream).
"""
import math
from dataclasses import dataclass

import numpy as np

from .motion_model import GRAVITY_M_S2


@dataclass(frozen=True)
class RestSettings:
    window_s: float                  # the rest window before the first frame (0: none)
    sigma_rad_s: float               # the prior's std once calibrated (or calibrated beforehand)
    uncalibrated_sigma_rad_s: float  # the prior's std when the window moved or was too short
    max_gyro_std_rad_s: float        # at rest: the gyro's std about its mean, per axis, within this ...
    max_rate_rad_s: float            # ... its mean's norm within this ...
    max_accel_m_s2: float            # ... and the mean specific force's norm within this of gravity


@dataclass
class GyroCalibration:
    bias_rad_s: np.ndarray           # (3,) the gyro bias prior's mean
    sigma_rad_s: float               # its std per axis
    calibrated: bool
    detail: str                      # what was measured, and why it was not calibrated


def calibrate_gyro_at_rest(gyro_rad_s, accel_m_s2, span_s: float, s: RestSettings) -> GyroCalibration:
    """The gyro bias prior from the samples of the rest window (rows in time order, span_s from the
    first sample to the frame); see the module's docstring."""
    if s.window_s <= 0:
        return GyroCalibration(np.zeros(3), s.sigma_rad_s, False, "no calibration at rest (window 0)")
    gyro, accel = np.asarray(gyro_rad_s, float).reshape(-1, 3), np.asarray(accel_m_s2, float).reshape(-1, 3)
    n = len(gyro)
    if n < 2 or span_s < s.window_s:
        return _uncalibrated(s, f"the IMU samples before the first frame span {span_s:.2f} s ({n} samples), "
                                f"less than the {s.window_s:g} s window")
    mean, std = gyro.mean(axis=0), gyro.std(axis=0, ddof=1)
    force = float(np.linalg.norm(accel.mean(axis=0)))
    figures = (f"gyro mean {np.array2string(mean, precision=5)} rad/s, std {np.array2string(std, precision=5)} "
               f"rad/s, specific force {force:.3f} m/s^2 over {span_s:.2f} s ({n} samples)")
    moved = []
    if std.max() > s.max_gyro_std_rad_s:
        moved.append(f"gyro std {std.max():.4f} > {s.max_gyro_std_rad_s:g} rad/s")
    if np.linalg.norm(mean) > s.max_rate_rad_s:
        moved.append(f"mean rate {np.linalg.norm(mean):.4f} > {s.max_rate_rad_s:g} rad/s")
    if abs(force - GRAVITY_M_S2) > s.max_accel_m_s2:
        moved.append(f"specific force {force:.3f} m/s^2 off gravity by more than {s.max_accel_m_s2:g}")
    if moved:
        return _uncalibrated(s, "the robot moved during the rest window (" + "; ".join(moved) + "): " + figures)
    sigma = max(s.sigma_rad_s, float(std.max()) / math.sqrt(n))
    return GyroCalibration(mean, sigma, True, "calibrated at rest: " + figures)


def _uncalibrated(s: RestSettings, why: str) -> GyroCalibration:
    return GyroCalibration(np.zeros(3), s.uncalibrated_sigma_rad_s, False,
                           f"gyro not calibrated, its bias prior zero within {s.uncalibrated_sigma_rad_s:g} rad/s: "
                           + why)
