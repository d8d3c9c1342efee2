"""Self-collision of the snake's modules as capsules: segment-segment distance less both radii.

Module 0 is the head (frames 0-1), module i the link between frames i and i + 1 (chain.py); each is
a capsule of the robot's link radius around that segment, as in the MJCF and the URDF. Neighbours
(modules i and i + 1) share a joint and always touch there; every other pair must stay apart.
Pure numpy, on any batch of postures: the planner's cost and checks, the tests and bench/ all call
these functions.
"""
import numpy as np

#: Segments shorter than this (m) are treated as points.
_EPS = 1e-12


def segment_distances(p1, q1, p2, q2) -> np.ndarray:
    """Shortest distance between segments p1-q1 and p2-q2 ((..., 3) each, broadcast): the closest
    points of Ericson, Real-Time Collision Detection, 5.1.9, vectorised."""
    p1, q1, p2, q2 = (np.asarray(x, float) for x in (p1, q1, p2, q2))
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = np.einsum("...k,...k->...", d1, d1)
    e = np.einsum("...k,...k->...", d2, d2)
    f = np.einsum("...k,...k->...", d2, r)
    c = np.einsum("...k,...k->...", d1, r)
    b = np.einsum("...k,...k->...", d1, d2)
    a_ok, e_ok = a > _EPS, e > _EPS
    a_safe, e_safe = np.where(a_ok, a, 1.0), np.where(e_ok, e, 1.0)
    denom = a * e - b * b
    # s on segment 1 for the infinite lines (0 when parallel: any s works, t is then clamped)
    s = np.where(denom > _EPS * np.maximum(a * e, _EPS), (b * f - c * e) / np.where(denom > 0, denom, 1.0), 0.0)
    s = np.clip(s, 0.0, 1.0)
    t = (b * s + f) / e_safe
    # t outside [0, 1]: clamp it and recompute s for the clamped t
    s = np.where(t < 0.0, np.clip(-c / a_safe, 0.0, 1.0), np.where(t > 1.0, np.clip((b - c) / a_safe, 0.0, 1.0), s))
    t = np.clip(t, 0.0, 1.0)
    # degenerate segments: a point against a segment (or a point)
    s = np.where(a_ok, s, 0.0)
    t = np.where(a_ok, t, np.clip(f / e_safe, 0.0, 1.0))
    t = np.where(e_ok, t, 0.0)
    s = np.where(e_ok | ~a_ok, s, np.clip(-c / a_safe, 0.0, 1.0))
    gap = (p1 + d1 * s[..., None]) - (p2 + d2 * t[..., None])
    return np.sqrt(np.einsum("...k,...k->...", gap, gap))


def module_pairs(num_modules: int, moving_below: int = None) -> np.ndarray:
    """(k, 2) pairs (i, j), i < j - 1, of modules that must not touch; with moving_below = m only
    the pairs with a module that moves when m modules are active (i < m)."""
    i, j = np.triu_indices(int(num_modules), k=2)
    keep = np.ones(len(i), bool) if moving_below is None else i < int(moving_below)
    return np.stack([i[keep], j[keep]], axis=1)


def clearances(positions, radius_m: float, pairs) -> np.ndarray:
    """(..., k) capsule clearance (m) of each pair for frame positions (..., F, 3): segment
    distance less two radii; < 0 is an overlap."""
    p = np.asarray(positions, float)
    i, j = np.asarray(pairs, int).T
    return segment_distances(p[..., i, :], p[..., i + 1, :], p[..., j, :], p[..., j + 1, :]) - 2.0 * radius_m


def worst_clearance(positions, radius_m: float, pairs=None):
    """(clearance (m), (module i, module j)) of the closest non-adjacent pair over every posture
    of positions (..., F, 3)."""
    p = np.asarray(positions, float)
    pairs = module_pairs(p.shape[-2] - 1) if pairs is None else np.asarray(pairs, int)
    if len(pairs) == 0:
        return np.inf, None
    c = clearances(p, radius_m, pairs).reshape(-1, len(pairs))
    k = int(np.argmin(c.min(axis=0)))
    return float(c[:, k].min()), (int(pairs[k, 0]), int(pairs[k, 1]))
