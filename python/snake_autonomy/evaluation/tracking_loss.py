"""Tracking-loss intervals: where the estimate cannot be trusted, flagged and kept out of the statistics.

Sources (thesis 4.1 failure modes: low texture, dark regions, head impact, jerky gait transitions):
- ``null``: a quaternion of zero norm (RTAB-Map's null transform). NaN/inf rows are not markers: the
  readers refuse them (row_checks.py);
- ``covariance``: an Odometry message whose pose covariance diagonal reaches the loss threshold
  (RTAB-Map publishes 9999 when odometry is lost);
- ``gap``: consecutive estimate stamps further apart than ``max_gap_s``; by default (None) that is
  max(1 s, 20 x the median period), so a 30 Hz VIO losing 1 s is flagged and a keyframe file is not;
- ``pose_stale``: the waypoint tracker reported the pose stale (TrackingStatus.pose_stale).

An interval ``(start_s, end_s)`` is open: its ends are the last trusted sample before the loss and the
first trusted one after it, which are kept. An APE pair at t is excluded when start < t < end; an RPE
pair (t_i, t_j) is excluded when the interval overlaps it (start < t_j and end > t_i), because a
relative motion measured across a loss is meaningless.
"""
from dataclasses import dataclass
from typing import Iterable, List, Optional, Sequence

import numpy as np


@dataclass(frozen=True)
class LossInterval:
    start_s: float
    end_s: float
    kind: str  # null | covariance | gap | pose_stale

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s

    def to_dict(self) -> dict:
        return {"start": self.start_s, "end": self.end_s, "duration": self.duration_s, "kind": self.kind}


def null_pose_mask(xyz: np.ndarray, quat_wxyz: np.ndarray, quat_norm_min: float = 1e-6) -> np.ndarray:
    """True where a pose is not a pose: any NaN/inf, or a quaternion of (near) zero norm."""
    finite = np.isfinite(xyz).all(axis=1) & np.isfinite(quat_wxyz).all(axis=1)
    norm = np.linalg.norm(np.nan_to_num(quat_wxyz), axis=1)
    return ~finite | (norm < quat_norm_min)


def intervals_from_mask(stamps: np.ndarray, lost: np.ndarray, kind: str) -> List[LossInterval]:
    """One interval per run of lost samples, bounded by the trusted samples around it.

    A run at the start (end) of the data begins (ends) at its own first (last) lost stamp.
    """
    stamps = np.asarray(stamps, dtype=float)
    lost = np.asarray(lost, dtype=bool)
    intervals = []
    n = len(stamps)
    i = 0
    while i < n:
        if not lost[i]:
            i += 1
            continue
        j = i
        while j + 1 < n and lost[j + 1]:
            j += 1
        start = stamps[i - 1] if i > 0 else stamps[i]
        end = stamps[j + 1] if j + 1 < n else stamps[j]
        intervals.append(LossInterval(float(start), float(end), kind))
        i = j + 1
    return intervals


AUTO_GAP_MIN_S = 1.0
AUTO_GAP_PERIODS = 20.0


def auto_max_gap(stamps: np.ndarray) -> float:
    """max(1 s, 20 x the median period of the stamps)."""
    stamps = np.sort(np.asarray(stamps, dtype=float))
    if len(stamps) < 2:
        return AUTO_GAP_MIN_S
    return max(AUTO_GAP_MIN_S, AUTO_GAP_PERIODS * float(np.median(np.diff(stamps))))


def gap_intervals(stamps: np.ndarray, max_gap_s: Optional[float] = None) -> List[LossInterval]:
    """Intervals between consecutive stamps further apart than max_gap_s (None: auto_max_gap; <= 0: off)."""
    stamps = np.asarray(stamps, dtype=float)
    if len(stamps) < 2:
        return []
    if max_gap_s is None:
        max_gap_s = auto_max_gap(stamps)
    if max_gap_s <= 0:
        return []
    order = np.sort(stamps)
    gaps = np.nonzero(np.diff(order) > max_gap_s)[0]
    return [LossInterval(float(order[k]), float(order[k + 1]), "gap") for k in gaps]


def merge_intervals(intervals: Iterable[LossInterval]) -> List[LossInterval]:
    """Sorted by start; overlapping intervals are kept separate (their kinds differ) but ordered."""
    return sorted(intervals, key=lambda iv: (iv.start_s, iv.end_s, iv.kind))


def points_in_loss(stamps: np.ndarray, intervals: Sequence[LossInterval]) -> np.ndarray:
    """True for every stamp strictly inside some interval (APE exclusion)."""
    stamps = np.asarray(stamps, dtype=float)
    mask = np.zeros(len(stamps), dtype=bool)
    for iv in intervals:
        mask |= (stamps > iv.start_s) & (stamps < iv.end_s)
    return mask


def spans_in_loss(t_i: np.ndarray, t_j: np.ndarray, intervals: Sequence[LossInterval]) -> np.ndarray:
    """True for every pair (t_i, t_j) whose span overlaps some interval (RPE exclusion)."""
    lo = np.minimum(np.asarray(t_i, dtype=float), np.asarray(t_j, dtype=float))
    hi = np.maximum(np.asarray(t_i, dtype=float), np.asarray(t_j, dtype=float))
    mask = np.zeros(len(lo), dtype=bool)
    for iv in intervals:
        mask |= (iv.start_s < hi) & (iv.end_s > lo)
    return mask
