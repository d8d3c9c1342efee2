"""Which rows of an input trajectory are poses, which are tracking-loss markers, which are refused.

Tracking-loss markers (documented, counted and reported as loss, see tracking_loss.py):
- ``null``: a quaternion of zero norm (RTAB-Map's null transform: all-zero pose);
- ``covariance``: an Odometry covariance at or above the threshold (readers.py).

Everything else that is not a pose is refused whole, with the input, row and value (EvaluationError):
- a NaN or infinite stamp, position or quaternion component (not a marker: a broken writer);
- a position component beyond ``MAX_POSITION_M`` (a 1e308 row would make every statistic inf);
- a quaternion whose norm is off 1 by more than ``QUAT_NORM_TOLERANCE`` (and not zero);
- stamps that decrease (association would pair the wrong poses): refused, not sorted, because a
  reordered input usually means two clocks or two sources mixed in one file.

A stamp that repeats the previous one is kept, with a warning: evo keeps it too, and real reference
data has them (TUM fr2_desk ground truth: 1, EuRoC V102 estimate: 4), so refusing or dropping them
would change statistics that must equal evo's.
"""
from typing import List

import numpy as np

from .errors import EvaluationError

MAX_POSITION_M = 1e5
QUAT_NORM_TOLERANCE = 0.01
NULL_QUAT_NORM = 1e-6   # below this a quaternion is the null-pose marker


def null_marker_mask(quat: np.ndarray) -> np.ndarray:
    """True where the quaternion is the null-pose marker (finite, norm below NULL_QUAT_NORM)."""
    quat = np.asarray(quat, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        return np.isfinite(quat).all(axis=1) & (np.linalg.norm(quat, axis=1) < NULL_QUAT_NORM)


def _row(name: str, k: int, stamps) -> str:
    stamp = stamps[k]
    return f"{name}: pose {k} (row {k + 1} of the poses, stamp {stamp!r})"


def check_rows(name: str, stamps, xyz, quat) -> List[str]:
    """Raises EvaluationError for the first row that is neither a pose nor a loss marker (see above);
    returns the warnings (repeated stamps).

    ``quat`` in any component order (the norm and finiteness do not depend on it)."""
    stamps = np.asarray(stamps, dtype=float).reshape(-1)
    xyz = np.asarray(xyz, dtype=float)
    quat = np.asarray(quat, dtype=float)
    bad = np.nonzero(~np.isfinite(stamps))[0]
    if len(bad):
        raise EvaluationError(f"{_row(name, int(bad[0]), stamps)}: the stamp is not a finite number")
    for label, arr in (("position", xyz), ("quaternion", quat)):
        bad = np.nonzero(~np.isfinite(arr).all(axis=1))[0]
        if len(bad):
            k = int(bad[0])
            raise EvaluationError(f"{_row(name, k, stamps)}: non-finite {label} {arr[k].tolist()} "
                                  f"(NaN/inf is not a tracking-loss marker; {len(bad)} such rows)")
    bad = np.nonzero(np.abs(xyz).max(axis=1) > MAX_POSITION_M)[0]
    if len(bad):
        k = int(bad[0])
        raise EvaluationError(f"{_row(name, k, stamps)}: position {xyz[k].tolist()} beyond "
                              f"+-{MAX_POSITION_M:g} m ({len(bad)} such rows)")
    with np.errstate(over="ignore"):
        norm = np.linalg.norm(quat / np.maximum(np.abs(quat).max(axis=1, keepdims=True), 1e-300), axis=1) \
            * np.abs(quat).max(axis=1)
    bad = np.nonzero((np.abs(norm - 1.0) > QUAT_NORM_TOLERANCE) & (norm >= NULL_QUAT_NORM))[0]
    if len(bad):
        k = int(bad[0])
        raise EvaluationError(f"{_row(name, k, stamps)}: quaternion {quat[k].tolist()} is not a unit quaternion "
                              f"(norm {norm[k]:.6g}, tolerance {QUAT_NORM_TOLERANCE:g}; a zero quaternion "
                              f"marks a tracking loss) ({len(bad)} such rows)")
    steps = np.diff(stamps)
    bad = np.nonzero(steps < 0)[0]
    if len(bad):
        k = int(bad[0]) + 1
        raise EvaluationError(f"{_row(name, k, stamps)}: the stamp goes back from the previous one "
                              f"{stamps[k - 1]!r} (stamps must not decrease; {len(bad)} such rows)")
    repeated = np.nonzero(steps == 0)[0]
    if len(repeated):
        k = int(repeated[0]) + 1
        return [f"{_row(name, k, stamps)}: the stamp repeats the previous one ({len(repeated)} repeated "
                "stamps, kept as evo keeps them)"]
    return []
