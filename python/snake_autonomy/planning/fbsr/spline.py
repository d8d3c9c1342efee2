"""The one-parameter cubic of each active joint (paper eq. 3-8; eq. 8 as
a = -2b / (3 t_end): one free parameter b per joint).

    theta(t) = a t^3 + b t^2 + theta0,  a = -2 b / (3 t_end)       (c = 0, d = theta0)

so theta'(0) = theta'(t_end) = 0 and theta(t_end) = theta0 + b t_end^2 / 3. The planner optimises
the end offset delta = theta(t_end) - theta0 = b t_end^2 / 3 (the same single parameter, better
scaled). theta' = 2 b t (1 - t / t_end) keeps one sign on [0, t_end]: the joint moves monotonically
from theta0 to theta(t_end), so the joint limits over the whole trajectory are the bounds
lower <= theta0 + delta <= upper, simple box constraints on delta.
"""
import numpy as np


def coefficients(delta, t_end_s: float):
    """(a, b) of eq. 3 and 8 for end offsets delta (rad)."""
    b = 3.0 * np.asarray(delta, float) / t_end_s ** 2
    return -2.0 * b / (3.0 * t_end_s), b


def positions(theta0, delta, t_end_s: float, t_s) -> np.ndarray:
    """(len(t), n) joint angles at times t (clipped to [0, t_end])."""
    a, b = coefficients(delta, t_end_s)
    t = np.clip(np.atleast_1d(np.asarray(t_s, float)), 0.0, t_end_s)[:, None]
    return a * t ** 3 + b * t ** 2 + np.asarray(theta0, float)


def velocities(delta, t_end_s: float, t_s) -> np.ndarray:
    """(len(t), n) joint velocities (eq. 5 with c = 0)."""
    a, b = coefficients(delta, t_end_s)
    t = np.clip(np.atleast_1d(np.asarray(t_s, float)), 0.0, t_end_s)[:, None]
    return 3.0 * a * t ** 2 + 2.0 * b * t


def delta_bounds(theta0, lower, upper, margin_rad: float = 0.0):
    """Per-joint (lo, hi) bounds on delta that keep theta within [lower + m, upper - m]."""
    theta0 = np.asarray(theta0, float)
    lo = np.asarray(lower, float) + margin_rad - theta0
    hi = np.asarray(upper, float) - margin_rad - theta0
    return np.minimum(lo, 0.0), np.maximum(hi, 0.0)
