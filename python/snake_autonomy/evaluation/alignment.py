"""Aligning the estimate to the reference before the error is measured.

``se3``, ``sim3`` and ``origin`` are evo's own (Umeyama; origin-to-origin). ``yaw`` is the 4-DoF
alignment visual-inertial odometry needs and evo lacks: gravity makes roll and pitch observable, so
only a rotation about z and a translation are unknown. It is the closed-form least-squares solution
of

    min_{theta, t}  sum_i || Rz(theta) p_i + t - q_i ||^2

for estimate positions p_i and reference positions q_i: with centred points p'_i, q'_i,
theta = atan2(sum(p'_x q'_y - p'_y q'_x), sum(p'_x q'_x + p'_y q'_y)) (the 2-D Umeyama/Kabsch
solution, always a proper rotation), and t = mean(q) - Rz(theta) mean(p), whose z part is the mean
height difference.
"""
from typing import Optional, Tuple

import numpy as np

from .errors import EvaluationError

ALIGN_MODES = ("none", "se3", "sim3", "origin", "yaw")
MIN_PAIRS = {"se3": 3, "sim3": 3, "yaw": 3, "origin": 1, "none": 1}


def rot_z(theta_rad: float) -> np.ndarray:
    c, s = np.cos(theta_rad), np.sin(theta_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def yaw_alignment(est_xyz: np.ndarray, ref_xyz: np.ndarray) -> Tuple[float, np.ndarray]:
    """(theta_rad, t) minimising sum |Rz(theta) est + t - ref|^2 over matched positions (n x 3).

    Raises EvaluationError for fewer than 3 pairs or when the estimate's xy positions do not
    spread (a yaw is then undetermined).
    """
    est_xyz = np.asarray(est_xyz, dtype=float)
    ref_xyz = np.asarray(ref_xyz, dtype=float)
    if est_xyz.shape != ref_xyz.shape or est_xyz.ndim != 2 or est_xyz.shape[1] != 3:
        raise ValueError(f"need two n x 3 arrays of the same shape, got {est_xyz.shape} and {ref_xyz.shape}")
    if len(est_xyz) < MIN_PAIRS["yaw"]:
        raise EvaluationError(f"yaw alignment needs at least 3 matched pairs, got {len(est_xyz)}")
    mu_p, mu_q = est_xyz.mean(axis=0), ref_xyz.mean(axis=0)
    p, q = est_xyz - mu_p, ref_xyz - mu_q
    sin_sum = float(np.sum(p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]))
    cos_sum = float(np.sum(p[:, 0] * q[:, 0] + p[:, 1] * q[:, 1]))
    if np.hypot(sin_sum, cos_sum) < 1e-12 * max(1.0, float(np.sum(p[:, :2] ** 2))):
        raise EvaluationError("yaw alignment is undetermined: the matched xy positions do not spread "
                              "(pure vertical motion or a single point); use --align origin or none")
    theta = float(np.arctan2(sin_sum, cos_sum))
    t = mu_q - rot_z(theta) @ mu_p
    return theta, t


def align(traj_est, traj_ref, mode: str, n_to_align: int = -1) -> Optional[np.ndarray]:
    """Aligns traj_est (an evo trajectory, changed in place) to traj_ref; returns the 4x4 applied.

    Positions are already associated pair by pair. ``n_to_align`` > 0 uses only the first n pairs
    (as evo's --n_to_align). Returns None for mode 'none'. For se3/sim3/origin prefer passing the
    mode to evo's ape()/rpe() (metrics.evaluate does): this function is for callers who only align.
    """
    from evo.core import lie_algebra  # lazy: evo is heavy and only this path needs it

    if mode not in ALIGN_MODES:
        raise EvaluationError(f"unknown alignment {mode!r}: use one of {', '.join(ALIGN_MODES)}")
    check_pairs(traj_est.num_poses, mode)
    if mode == "none":
        return None
    if mode == "origin":
        return traj_est.align_origin(traj_ref)
    if mode in ("se3", "sim3"):
        r, t, s = traj_est.align(traj_ref, correct_scale=(mode == "sim3"), n=n_to_align)
        return lie_algebra.sim3(r, t, s)
    n = traj_est.num_poses if n_to_align is None or n_to_align < 0 else n_to_align
    theta, t = yaw_alignment(traj_est.positions_xyz[:n], traj_ref.positions_xyz[:n])
    transform = lie_algebra.se3(rot_z(theta), t)
    traj_est.transform(transform)
    return transform


def check_pairs(num_pairs: int, mode: str) -> None:
    need = MIN_PAIRS.get(mode, 1)
    if num_pairs < need:
        raise EvaluationError(f"{mode} alignment needs at least {need} matched pairs, found {num_pairs}: "
                              "widen --t-max-diff, check --t-offset, or use --align none")


def yaw_of(transform: np.ndarray) -> float:
    """Rotation angle about z (rad) of a 4x4 transform."""
    return float(np.arctan2(transform[1, 0], transform[0, 0]))
