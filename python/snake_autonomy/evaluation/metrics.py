"""evaluate(): association, alignment and APE/RPE by evo, with tracking loss kept out of the numbers.

The path is evo_ape's / evo_rpe's own (``PoseTrajectory3D.sync_with`` then ``evo.main_ape.ape`` or
``evo.main_rpe.rpe``), so with no tracking loss in the data the statistics are evo's to the bit.
What is added: yaw-only alignment (alignment.py), exclusion of tracking-loss intervals
(tracking_loss.py) and per-segment statistics (segments.py).
"""
import copy
import logging
from dataclasses import asdict, dataclass, field
from typing import Dict, List, Optional, Sequence, Union

import numpy as np

from . import alignment as alignment_mod
from .errors import EvaluationError
from .readers import LoadedTrajectory
from .segments import SEGMENT_KEYS, StatusSample, segment_statistics, spans, status_loss_intervals
from .stats import STAT_KEYS, statistics
from .tracking_loss import LossInterval, gap_intervals, merge_intervals, points_in_loss, spans_in_loss

METRICS = ("ape", "rpe")
# our name -> evo PoseRelation value; evo's CLI names are accepted too
RELATIONS = {"trans": "translation part", "trans_part": "translation part",
             "angle_deg": "rotation angle in degrees", "angle_rad": "rotation angle in radians",
             "rot": "rotation part without unit", "rot_part": "rotation part without unit",
             "full": "full transformation", "point_distance": "point distance"}
DELTA_UNITS = {"f": "frames", "m": "m"}
SYNC_METHODS = {"nearest": "nearest_time", "interpolation": "interpolation"}
# Option ranges: association windows and gaps up to an hour, clock offsets up to 1e10 s (any epoch),
# RPE steps up to a million frames or metres.
MAX_WINDOW_S = 3600.0
MAX_T_OFFSET_S = 1e10
MAX_DELTA = 1e6


def _finite_in(v, lo: float, hi: float) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) and lo <= v <= hi

logger = logging.getLogger(__name__)


@dataclass
class EvaluationOptions:
    """What evo_ape / evo_rpe would be asked, plus the tracking-loss settings.

    Defaults are evo's (no alignment, t_max_diff 0.01 s, translation part, delta 1 frame).
    """
    metric: str = "ape"            # ape | rpe
    relation: str = "trans"        # trans | angle_deg | angle_rad | rot | full | point_distance
    align: str = "none"            # none | se3 | sim3 | origin | yaw
    n_to_align: int = -1           # pairs used for alignment, from the start (-1: all)
    t_max_diff_s: float = 0.01     # association window
    t_offset_s: float = 0.0        # added to the estimate's stamps for association
    sync: str = "nearest"          # nearest | interpolation
    delta: float = 1.0             # RPE step
    delta_unit: str = "f"          # f (frames) | m (metres of path)
    all_pairs: bool = False        # RPE: all pairs instead of consecutive ones
    max_gap_s: Optional[float] = None  # stamps further apart are a loss (None: auto, 0: off)
    exclude_loss: bool = True      # keep tracking-loss intervals out of alignment and statistics
    segment_keys: Sequence[str] = SEGMENT_KEYS

    def validate(self) -> None:
        """Raises EvaluationError naming every bad option at once."""
        errors = []
        if self.metric not in METRICS:
            errors.append(f"metric={self.metric!r} (use {' or '.join(METRICS)})")
        if self.relation not in RELATIONS:
            errors.append(f"relation={self.relation!r} (use one of {', '.join(RELATIONS)})")
        if self.align not in alignment_mod.ALIGN_MODES:
            errors.append(f"align={self.align!r} (use one of {', '.join(alignment_mod.ALIGN_MODES)})")
        if not _finite_in(self.t_max_diff_s, 0.0, MAX_WINDOW_S):
            errors.append(f"t_max_diff_s={self.t_max_diff_s} (must be in 0..{MAX_WINDOW_S:g} s)")
        if not _finite_in(self.t_offset_s, -MAX_T_OFFSET_S, MAX_T_OFFSET_S):
            errors.append(f"t_offset_s={self.t_offset_s} (must be a finite number of seconds within "
                          f"+-{MAX_T_OFFSET_S:g})")
        if self.max_gap_s is not None and not _finite_in(self.max_gap_s, 0.0, MAX_WINDOW_S):
            errors.append(f"max_gap_s={self.max_gap_s} (must be in 0..{MAX_WINDOW_S:g} s; 0 turns gaps off)")
        if self.sync not in SYNC_METHODS:
            errors.append(f"sync={self.sync!r} (use nearest or interpolation)")
        if self.delta_unit not in DELTA_UNITS:
            errors.append(f"delta_unit={self.delta_unit!r} (use f or m)")
        if not (_finite_in(self.delta, 0.0, MAX_DELTA) and self.delta > 0):
            errors.append(f"delta={self.delta} (must be > 0 and at most {MAX_DELTA:g})")
        elif self.delta_unit == "f" and float(self.delta) != int(self.delta):
            errors.append(f"delta={self.delta} (must be a whole number of frames)")
        if isinstance(self.n_to_align, bool) or not isinstance(self.n_to_align, int) \
                or self.n_to_align == 0 or self.n_to_align < -1:
            errors.append(f"n_to_align={self.n_to_align} (use -1 for all, or a positive count)")
        bad_keys = [k for k in self.segment_keys if k not in SEGMENT_KEYS]
        if bad_keys:
            errors.append(f"segment_keys={bad_keys} (use {', '.join(SEGMENT_KEYS)})")
        if errors:
            raise EvaluationError("invalid options: " + "; ".join(errors))


@dataclass
class EvaluationResult:
    """Everything evaluate() found. Arrays are per pair, in time order."""
    options: EvaluationOptions
    ref_name: str
    est_name: str
    stats: Dict[str, float]              # max mean median min rmse sse std over included pairs
    pairs: int                           # pairs in the statistics
    excluded_pairs: int                  # pairs dropped for tracking loss
    unit: str                            # m, deg, rad or '' (evo's unit of the metric)
    title: str                           # evo's title of the metric, with our alignment note
    errors: np.ndarray                   # error of each included pair
    stamps_s: np.ndarray                 # estimate stamp of each included pair (RPE: the later pose)
    traj_ref: object                     # associated reference (evo PoseTrajectory3D)
    traj_est: object                     # associated estimate, aligned
    alignment: Optional[np.ndarray]      # 4x4 applied to the estimate (Sim(3) for sim3), or None
    loss_intervals: List[LossInterval] = field(default_factory=list)
    segments: Dict[str, List[dict]] = field(default_factory=dict)
    segment_spans: Dict[str, list] = field(default_factory=dict)
    traj_ref_full: object = None         # the whole reference, for plots
    evo_result: object = None            # evo's Result (all pairs of the evo call)

    def to_dict(self) -> dict:
        """The JSON document: the statistics at top level, then how they were obtained."""
        doc = {k: float(self.stats[k]) for k in STAT_KEYS}
        doc.update({
            "pairs": int(self.pairs),
            "excluded_pairs": int(self.excluded_pairs),
            "unit": self.unit,
            "title": self.title,
            "reference": self.ref_name,
            "estimate": self.est_name,
            "options": {k: (list(v) if isinstance(v, (tuple, list)) else v)
                        for k, v in asdict(self.options).items()},
            "alignment": None if self.alignment is None else np.asarray(self.alignment).tolist(),
            "loss_intervals": [iv.to_dict() for iv in self.loss_intervals],
            "segments": self.segments,
        })
        if self.alignment is not None:
            r = np.asarray(self.alignment)[:3, :3]
            doc["alignment_scale"] = float(np.cbrt(np.linalg.det(r)))
            doc["alignment_yaw_deg"] = float(np.degrees(alignment_mod.yaw_of(self.alignment)))
        return doc


def evaluate(ref: Union[LoadedTrajectory, object], est: Union[LoadedTrajectory, object],
             options: Optional[EvaluationOptions] = None,
             status: Optional[Sequence[StatusSample]] = None,
             loss_intervals: Sequence[LossInterval] = ()) -> EvaluationResult:
    """Evaluates an estimate against a reference; the inputs are not modified.

    ``ref``/``est``: evo PoseTrajectory3D or LoadedTrajectory (readers.load_trajectory).
    ``status``: TrackingStatus samples (segments.read_tracking_status) for per-segment statistics.
    ``loss_intervals``: extra tracking-loss intervals (estimate time) to exclude.
    Raises EvaluationError for anything the user can fix.
    """
    from evo.core import metrics as evo_metrics  # lazy: evo is heavy and only this path needs it
    from evo.core.sync import SyncMethod
    from evo.core.trajectory import PoseTrajectory3D

    options = options or EvaluationOptions()
    options.validate()
    ref_name, traj_ref, ref_loss = _unpack(ref, "reference")
    est_name, traj_est, est_loss = _unpack(est, "estimate")
    for name, traj in ((ref_name, traj_ref), (est_name, traj_est)):
        if not isinstance(traj, PoseTrajectory3D):
            raise EvaluationError(f"{name}: a trajectory with timestamps is needed, got {type(traj).__name__}")
    status = list(status or [])

    known = list(est_loss) + list(loss_intervals)
    # a run of dropped poses is also a gap in what is left: report it once, with its cause
    gaps = [g for g in gap_intervals(traj_est.timestamps, options.max_gap_s)
            if not any(iv.start_s <= g.start_s and g.end_s <= iv.end_s for iv in known)]
    intervals = known + gaps
    intervals += status_loss_intervals(status)
    intervals = merge_intervals(intervals)
    del ref_loss  # reference losses only remove poses (nothing is associated with them)

    traj_ref_full = copy.deepcopy(traj_ref)
    try:
        ref_sync, est_sync = traj_ref.sync_with(
            traj_est, sync_method=SyncMethod(SYNC_METHODS[options.sync]),
            max_diff=options.t_max_diff_s, offset_2=options.t_offset_s)
    except Exception as exc:
        if type(exc).__name__ != "SyncException":
            raise
        raise EvaluationError(no_match_message(traj_ref, traj_est, options, ref_name, est_name)) from None

    excluded = 0
    if options.exclude_loss and intervals:
        inside = points_in_loss(est_sync.timestamps, intervals)
        if inside.all():
            raise EvaluationError(f"all {len(inside)} matched pairs fall in tracking-loss intervals; "
                                  "nothing left to evaluate (see --max-gap, or --keep-loss)")
        if inside.any():
            keep = np.nonzero(~inside)[0]
            ref_sync.reduce_to_ids(keep)
            est_sync.reduce_to_ids(keep)
            excluded = int(inside.sum())
    alignment_mod.check_pairs(est_sync.num_poses, options.align)
    if options.metric == "rpe" and est_sync.num_poses < 2:
        raise EvaluationError(f"RPE needs at least 2 matched pairs, found {est_sync.num_poses}")

    relation = evo_metrics.PoseRelation(RELATIONS[options.relation])
    evo_align = {"align": options.align in ("se3", "sim3"), "correct_scale": options.align == "sim3",
                 "align_origin": options.align == "origin", "n_to_align": options.n_to_align}
    transform = None
    if options.align == "yaw":
        transform = alignment_mod.align(est_sync, ref_sync, "yaw", options.n_to_align)
        evo_align["n_to_align"] = -1
    try:
        if options.metric == "ape":
            from evo.main_ape import ape
            res = ape(ref_sync, est_sync, relation, **evo_align)
            errors = np.asarray(res.np_arrays["error_array"], dtype=float)
            stamps = np.asarray(est_sync.timestamps, dtype=float)
            t_first = stamps
        else:
            from evo.main_rpe import rpe
            unit = evo_metrics.Unit(DELTA_UNITS[options.delta_unit])
            delta = int(options.delta) if options.delta_unit == "f" else float(options.delta)
            res = rpe(ref_sync, est_sync, relation, delta=delta, delta_unit=unit,
                      all_pairs=options.all_pairs, support_loop=True, **evo_align)
            errors = np.asarray(res.np_arrays["error_array"], dtype=float)
            # the same pairs evo used: same function, same (aligned) poses
            id_pairs = evo_metrics.id_pairs_from_delta(est_sync.poses_se3, delta, unit,
                                                       all_pairs=options.all_pairs)
            stamps_all = np.asarray(est_sync.timestamps, dtype=float)
            t_first = stamps_all[[i for i, _ in id_pairs]]
            stamps = stamps_all[[j for _, j in id_pairs]]
            if len(stamps) != len(errors):
                raise RuntimeError(f"RPE pairs ({len(stamps)}) and errors ({len(errors)}) differ")
    except EvaluationError:
        raise
    except Exception as exc:  # evo's Metrics/Filter/Geometry exceptions: bad delta, degenerate data
        if type(exc).__module__.startswith("evo"):
            raise EvaluationError(f"evo: {exc}") from None
        raise
    if "alignment_transformation_sim3" in res.np_arrays:
        transform = np.asarray(res.np_arrays["alignment_transformation_sim3"])

    stats = {k: float(res.stats[k]) for k in STAT_KEYS}
    if options.metric == "rpe" and options.exclude_loss and intervals:
        across = spans_in_loss(t_first, stamps, intervals)
        if across.all():
            raise EvaluationError("every RPE pair spans a tracking-loss interval; nothing left to evaluate")
        if across.any():
            errors, stamps = errors[~across], stamps[~across]
            excluded += int(across.sum())
            stats = statistics(errors)

    title = res.info.get("title", "")
    if options.align == "yaw":
        title = title.replace("(not aligned)", "(with yaw-only 4-DoF alignment)")
    if excluded:
        title += f"\n({excluded} pairs in tracking loss excluded)"
    unit_str = res.info.get("label", "").rpartition("(")[2].rstrip(")")
    result = EvaluationResult(
        options=options, ref_name=ref_name, est_name=est_name, stats=stats, pairs=len(errors),
        excluded_pairs=excluded, unit=unit_str, title=title, errors=errors, stamps_s=stamps,
        traj_ref=ref_sync, traj_est=est_sync, alignment=transform, loss_intervals=intervals,
        traj_ref_full=traj_ref_full, evo_result=res)
    if status:
        result.segments = segment_statistics(errors, stamps, status, options.segment_keys)
        end = float(traj_est.timestamps[-1])
        result.segment_spans = {k: spans(status, k, end) for k in options.segment_keys}
    return result


def _unpack(item, role: str):
    if isinstance(item, LoadedTrajectory):
        return item.name, copy.deepcopy(item.traj), list(item.loss_intervals)
    name = getattr(item, "name", None) or role
    return name, copy.deepcopy(item), []


def no_match_message(traj_ref, traj_est, options: EvaluationOptions, ref_name: str, est_name: str) -> str:
    """Why no timestamps matched, and which --t-max-diff / --t-offset would match, from the data."""
    from evo.core.sync import matching_time_indices  # lazy: evo is heavy and only this path needs it

    ref_t = np.sort(np.asarray(traj_ref.timestamps, dtype=float))
    est_t = np.asarray(traj_est.timestamps, dtype=float) + options.t_offset_s
    idx = np.clip(np.searchsorted(ref_t, est_t), 1, len(ref_t) - 1) if len(ref_t) > 1 else np.zeros(
        len(est_t), dtype=int)
    nearest = np.abs(ref_t[idx] - est_t)
    if len(ref_t) > 1:
        nearest = np.minimum(nearest, np.abs(ref_t[idx - 1] - est_t))
    lines = [f"no matching timestamps between {ref_name} and {est_name} with "
             f"--t-max-diff {options.t_max_diff_s:g} s and --t-offset {options.t_offset_s:g} s.",
             f"  reference spans {ref_t[0]:.3f} .. {ref_t[-1]:.3f} s; estimate (with offset) "
             f"{est_t.min():.3f} .. {est_t.max():.3f} s."]
    lines.append(f"  the closest stamps are {nearest.min():.6g} s apart (median {np.median(nearest):.6g} s): "
                 f"--t-max-diff {_round_up(nearest.min()):g} matches at least one pair, "
                 f"--t-max-diff {_round_up(np.median(nearest)):g} about half of the estimate.")
    offset = float(ref_t[0] - (est_t.min() - options.t_offset_s))
    n = len(matching_time_indices(np.sort(est_t - options.t_offset_s + offset), ref_t,
                                  options.t_max_diff_s)[0])
    lines.append(f"  their starts are {offset:.6f} s apart: --t-offset {offset:.6f} lines up their starts "
                 f"({n} pairs would match within --t-max-diff {options.t_max_diff_s:g}).")
    return "\n".join(lines)


def _round_up(x: float) -> float:
    """x rounded up to 2 significant digits (a window that really includes x)."""
    if x <= 0:
        return 0.0
    exp = np.floor(np.log10(x)) - 1
    return float(np.ceil(x / 10 ** exp) * 10 ** exp)
