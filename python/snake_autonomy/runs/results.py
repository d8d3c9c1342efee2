"""The results folder of a run, from plain arrays (no ROS): metrics, CSVs and the thesis's figures.

Used by the mission node (at the end of a run), by ``snake_autonomy report BAG`` (from a bag) and
by the simulator's batch runs. Inputs:

- ``waypoints``: sequence of (x_m, y_m, heading_rad).
- ``decisions``: mapping of equal-length arrays, one entry per 1 Hz tracker step. Required keys:
  ``t`` (s), ``waypoint_index`` (after the step), ``distance`` (m), ``yaw_error_abs``,
  ``yaw_error_rel``, ``yaw_error`` (rad). Optional: ``target_index`` (the waypoint the errors refer
  to), ``reached`` (bool), ``mode``, ``delta``, ``w``, ``gait`` (str), ``pose_stale`` (bool),
  ``true_distance`` and ``true_yaw_error_abs`` (the same errors from ground truth, simulator). When
  ``target_index``/``reached`` are absent they are inferred from increments of ``waypoint_index``.
  Steps with a stale pose carry NaN errors.
- ``trajectory``: mapping with ``t``, ``x``, ``y`` (and optionally ``yaw``) of the centre of mass,
  any rate; optionally ``x_true``, ``y_true`` (ground truth, drawn dashed on the trajectory figure).

Per waypoint the metrics give ``reached``, ``time_s`` (the time this waypoint took: from the previous
waypoint's reach, or the start, to its own; null when not reached), ``time_to_reach_s`` (from the start),
``final_distance_m``, ``final_yaw_error_deg`` (combined, Algorithm 1 line 8), ``final_yaw_error_abs_deg``
(against the waypoint heading) and, when the decisions carry ground truth, ``true_final_distance_m`` /
``true_final_yaw_error_abs_deg``.

Outputs (``write_results``): metrics.json, decisions.csv, trajectory.csv, trajectory.png (fig. 4.10
style: XY path with waypoints), distance_error.png, yaw_errors.png (abs, rel, combined; waypoint
segments shaded), yaw_error_vs_distance.png (figs. 4.16-4.20 style).
"""
import csv
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence

import numpy as np

from snake_autonomy.runs import plots as plotting

REQUIRED_DECISION_KEYS = ("t", "waypoint_index", "distance", "yaw_error_abs", "yaw_error_rel", "yaw_error")
REQUIRED_TRAJECTORY_KEYS = ("t", "x", "y")
DEG = 180.0 / math.pi


def _as_arrays(data: Mapping[str, Any], required: Sequence[str], what: str) -> Dict[str, np.ndarray]:
    if data is None:
        data = {}
    missing = [k for k in required if k not in data]
    if missing and any(len(data.get(k, ())) for k in data):
        raise ValueError(f"{what}: missing key(s) {', '.join(missing)} (have {', '.join(sorted(data))})")
    out = {}
    n = None
    for k, v in data.items():
        arr = np.asarray(v)
        if arr.dtype.kind in "iufb":
            arr = arr.astype(float) if k not in ("waypoint_index", "target_index", "mode") else arr.astype(int)
        if n is None:
            n = len(arr)
        elif len(arr) != n:
            raise ValueError(f"{what}: key {k!r} has {len(arr)} values, expected {n}")
        out[k] = arr
    for k in required:
        out.setdefault(k, np.zeros(0))
    return out


def normalise_decisions(decisions: Mapping[str, Any]) -> Dict[str, np.ndarray]:
    """Arrays of the decisions with ``target_index`` and ``reached`` filled in."""
    d = _as_arrays(decisions, REQUIRED_DECISION_KEYS, "decisions")
    idx = d["waypoint_index"].astype(int) if len(d["waypoint_index"]) else np.zeros(0, dtype=int)
    if "reached" in d:
        reached = d["reached"].astype(bool)
    else:
        prev = np.concatenate([[0], idx[:-1]]) if len(idx) else idx
        reached = idx > prev
    if "target_index" not in d:
        d["target_index"] = idx - reached.astype(int)
    d["reached"] = reached
    d["waypoint_index"] = idx
    d["target_index"] = d["target_index"].astype(int)
    return d


#: Path length counts a move once the centre of mass is this far from the last counted point. The
#: com_pose stream (100 Hz) carries the sidewinding body's own sway and a sawtooth of a few
#: centimetres (the base pose arrives at 30-120 Hz, the joints every cycle): summed raw, the star
#: mission's com_pose (12.9 m of straight legs) came to 129 m in `make demo`; counted every 5 cm, 22 m.
PATH_MIN_STEP_M = 0.05


class PathLength:
    """Running path length of (x, y) samples, counted in steps of at least PATH_MIN_STEP_M."""

    def __init__(self, min_step_m: float = PATH_MIN_STEP_M):
        self.min_step_m = float(min_step_m)
        self.length_m = 0.0
        self._last = None

    def add(self, x: float, y: float) -> None:
        if not (math.isfinite(x) and math.isfinite(y)):
            return
        if self._last is None:
            self._last = (x, y)
            return
        d = math.hypot(x - self._last[0], y - self._last[1])
        if d >= self.min_step_m:
            self.length_m += d
            self._last = (x, y)


def path_length(trajectory: Mapping[str, Any], min_step_m: float = PATH_MIN_STEP_M) -> float:
    path = PathLength(min_step_m)
    for x, y in zip(np.asarray(trajectory.get("x", []), float), np.asarray(trajectory.get("y", []), float)):
        path.add(float(x), float(y))
    return path.length_m


def _finite_or_none(v) -> Optional[float]:
    v = float(v)
    return v if math.isfinite(v) else None


def compute_metrics(waypoints: Sequence[Sequence[float]], decisions: Mapping[str, Any],
                    trajectory: Optional[Mapping[str, Any]] = None, outcome: str = "unknown",
                    t0: Optional[float] = None, extra: Optional[Dict[str, Any]] = None) -> Dict[str, Any]:
    """Per waypoint: reached or not, time to reach (from the run start), segment duration, final
    distance and yaw errors (at the step it was reached, else the last step that targeted it)."""
    d = normalise_decisions(decisions)
    t = d["t"]
    if t0 is None:
        if len(t):
            t0 = float(t[0])
        elif trajectory is not None and len(trajectory.get("t", [])):
            t0 = float(trajectory["t"][0])
        else:
            t0 = 0.0
    per_wp = []
    prev_reach_t = t0
    for i, wp in enumerate(waypoints):
        mask = d["target_index"] == i
        hit = np.flatnonzero(mask & d["reached"])
        entry: Dict[str, Any] = {"index": i, "x_m": float(wp[0]), "y_m": float(wp[1]),
                                 "heading_deg": float(wp[2]) * DEG, "reached": bool(len(hit))}
        if len(hit):
            j = int(hit[0])
            entry["time_to_reach_s"] = float(t[j] - t0)
            entry["segment_duration_s"] = float(t[j] - prev_reach_t)
            entry["time_s"] = entry["segment_duration_s"]
            prev_reach_t = float(t[j])
        else:
            finite = np.flatnonzero(mask & np.isfinite(d["distance"]))
            j = int(finite[-1]) if len(finite) else None
            entry["time_to_reach_s"] = None
            entry["segment_duration_s"] = None
            entry["time_s"] = None
        if j is not None:
            entry["final_distance_m"] = _finite_or_none(d["distance"][j])
            entry["final_yaw_error_abs_deg"] = _finite_or_none(d["yaw_error_abs"][j] * DEG)
            entry["final_yaw_error_rel_deg"] = _finite_or_none(d["yaw_error_rel"][j] * DEG)
            entry["final_yaw_error_deg"] = _finite_or_none(d["yaw_error"][j] * DEG)
            seg = d["distance"][mask]
            seg = seg[np.isfinite(seg)]
            entry["min_distance_m"] = float(seg.min()) if len(seg) else None
            if "true_distance" in d and "true_yaw_error_abs" in d:
                entry["true_final_distance_m"] = _finite_or_none(d["true_distance"][j])
                entry["true_final_yaw_error_abs_deg"] = _finite_or_none(d["true_yaw_error_abs"][j] * DEG)
        else:
            for k in ("final_distance_m", "final_yaw_error_abs_deg", "final_yaw_error_rel_deg",
                      "final_yaw_error_deg", "min_distance_m"):
                entry[k] = None
        per_wp.append(entry)
    stale = d.get("pose_stale")
    t_end = float(t[-1]) if len(t) else t0
    if trajectory is not None and len(trajectory.get("t", [])):
        t_end = max(t_end, float(np.asarray(trajectory["t"])[-1]))
    metrics = {
        "outcome": outcome,
        "num_waypoints": len(waypoints),
        "waypoints_reached": int(sum(e["reached"] for e in per_wp)),
        "all_reached": bool(per_wp) and all(e["reached"] for e in per_wp),
        "duration_s": t_end - t0,
        "num_decisions": int(len(t)),
        "stale_decisions": int(np.sum(np.asarray(stale, dtype=bool))) if stale is not None else 0,
        "path_length_m": path_length(trajectory) if trajectory is not None else None,
        "waypoints": per_wp,
    }
    if extra:
        metrics.update(extra)
    return metrics


def write_json_atomic(path, data) -> None:
    """Writes JSON so that a reader (or a kill) only ever sees a complete file."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=str(path.parent), prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(data, f, indent=2, allow_nan=False)
        f.write("\n")
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def _write_csv(path, columns: Dict[str, np.ndarray]) -> None:
    keys = list(columns)
    n = len(columns[keys[0]]) if keys else 0
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for i in range(n):
            w.writerow([columns[k][i] for k in keys])


def write_results(out_dir, waypoints, trajectory: Mapping[str, Any], decisions: Mapping[str, Any],
                  outcome: str = "unknown", meta: Optional[Dict[str, Any]] = None, plots: bool = True,
                  d_th: float = 0.35, psi_wp: float = math.radians(30), psi_turn: float = math.radians(40),
                  title: str = "") -> Dict[str, Path]:
    """Writes the results folder; returns {name: path}. Metrics are written before the figures, so a
    plotting failure never loses them."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    traj = _as_arrays(trajectory, REQUIRED_TRAJECTORY_KEYS, "trajectory")
    dec = normalise_decisions(decisions)
    t0 = None
    starts = [a[0] for a in (traj["t"], dec["t"]) if len(a)]
    if meta and meta.get("t_start") is not None:
        t0 = float(meta["t_start"])
    elif starts:
        t0 = float(min(starts))
    meta = dict(meta or {})
    extra = {"meta": meta}
    if "scouts" in meta:   # the scout stops at top level, as the batch simulator writes them
        extra["scouts"] = meta.pop("scouts")
    metrics = compute_metrics(waypoints, dec, traj, outcome, t0, extra=extra)
    paths = {"metrics": out / "metrics.json"}
    write_json_atomic(paths["metrics"], metrics)
    paths["decisions_csv"] = out / "decisions.csv"
    cols = {k: (v - t0 if k == "t" and t0 is not None else v) for k, v in dec.items()}
    _write_csv(paths["decisions_csv"], cols)
    paths["trajectory_csv"] = out / "trajectory.csv"
    _write_csv(paths["trajectory_csv"], {k: (v - t0 if k == "t" and t0 is not None else v) for k, v in traj.items()})
    if plots:
        paths.update(plotting.plot_all(out, waypoints, traj, dec, t0 or 0.0, d_th, psi_wp, psi_turn,
                                       title or (meta or {}).get("mission", "")))
    return paths
