"""The unicycle the rectilinear gait reduces to (Chang et al. II-B): constant forward speed v, turn
rate omega; a path of curvature c = omega / v. Poses are (x_m, y_m, theta_rad)."""
import math

import numpy as np


def arc_poses(curvature_per_m: float, length_m: float, spacing_m: float,
              start=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(N, 3) poses every spacing_m along an arc of constant curvature from `start` (included),
    the last one at length_m (negative: backwards along the arc)."""
    n = max(1, int(math.ceil(abs(length_m) / spacing_m)))
    s = np.linspace(0.0, length_m, n + 1)
    c = curvature_per_m
    if abs(c) < 1e-9:
        x, y, th = s, np.zeros_like(s), np.zeros_like(s)
    else:
        th = c * s
        x, y = np.sin(th) / c, (1.0 - np.cos(th)) / c
    x0, y0, t0 = start
    ct, st = math.cos(t0), math.sin(t0)
    return np.column_stack([x0 + ct * x - st * y, y0 + st * x + ct * y, t0 + th])


def predict(pose, v_m_s: float, omega_rad_s: float, dt_s: float):
    """Pose after dt_s at constant (v, omega) (exact integration)."""
    x, y, th = pose
    if abs(omega_rad_s) < 1e-9:
        return (x + v_m_s * dt_s * math.cos(th), y + v_m_s * dt_s * math.sin(th), th)
    th2 = th + omega_rad_s * dt_s
    r = v_m_s / omega_rad_s
    return (x + r * (math.sin(th2) - math.sin(th)), y - r * (math.cos(th2) - math.cos(th)), th2)


def wrap(angle_rad: float) -> float:
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi
