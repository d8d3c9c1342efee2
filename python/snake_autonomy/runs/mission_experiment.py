"""The thesis's four closed-loop experiments (chapter 4.2) on the simulated robot, in batch.

    results = run_experiment("star", seeds=[0, 1, 2, 3, 4], feedback="vio", out="results/sim/star")

| name | mission | starts |
|---|---|---|
| single | config/missions/single_waypoint.yaml (origin, heading 0) | the 13 of SINGLE_STARTS |
| star | config/missions/star.yaml (five vertices) | origin, heading 0 |
| bidirectional | config/missions/bidirectional.yaml (home and four targets, eight legs) | origin, heading 0 |
| disturbance | config/missions/disturbance.yaml (two waypoints, pushes and twists mid-leg) | origin, heading 0 |

Each run is a BatchRun (sim.batch) writing its own results folder OUT/<feedback>/seed<N>[_start<k>]/;
the experiment adds OUT/<feedback>/summary.json, summary.md (the table) and summary.png (every run's
ground-truth path over the waypoints, and the time each waypoint took). Acceptance: every
waypoint reached (within d_th and psi_wp: the tracker's own test) in every run, no roll-over, no
joint goal beyond a limit, and in the disturbance experiment recovery after every push and twist.
"""
import math
import os
import sys
import time
from multiprocessing import get_context
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np
from tqdm import tqdm

from snake_autonomy.runs.batch import BatchRun, RunSpec
from snake_autonomy.runs.plots import _pyplot
from snake_autonomy.runs.results import write_json_atomic

EXPERIMENTS = {
    "single": "single_waypoint",
    "star": "star",
    "bidirectional": "bidirectional",
    "disturbance": "disturbance",
}


def _single_starts() -> List[tuple]:
    """13 start poses (CoM x_m, y_m, heading_deg): 1.5, 2.5 and 3.5 m from the waypoint in turn, at
    bearings 27.7 deg apart all around it, headings spread by the golden angle (137.5 deg)."""
    out = []
    for i in range(13):
        r = (1.5, 2.5, 3.5)[i % 3]
        b = math.radians(i * 360.0 / 13 + 15.0)
        h = (i * 137.5) % 360.0 - 180.0
        out.append((round(r * math.cos(b), 3), round(r * math.sin(b), 3), round(h, 1)))
    return out


SINGLE_STARTS = _single_starts()


def runs_of(name: str, seeds: Sequence[int], feedback: str, starts: Optional[Sequence[int]] = None,
            **spec_kwargs) -> List[RunSpec]:
    """The runs of an experiment; `starts`: indices into SINGLE_STARTS (single only; None: all 13)."""
    if name not in EXPERIMENTS:
        raise ValueError(f"experiment: expected one of {', '.join(EXPERIMENTS)}, got {name!r}")
    poses = SINGLE_STARTS if name == "single" else [(0.0, 0.0, 0.0)]
    chosen = range(len(poses)) if starts is None or name != "single" else list(starts)
    bad = [k for k in chosen if not 0 <= k < len(poses)]
    if bad:
        raise ValueError(f"starts: {bad} out of range 0-{len(poses) - 1}")
    out = []
    for seed in seeds:
        for k in chosen:
            start = poses[k]
            label = f"seed{seed}" + (f"_start{k:02d}" if name == "single" else "")
            out.append(RunSpec(mission=EXPERIMENTS[name], seed=int(seed), feedback=feedback, start=start,
                               label=label, **spec_kwargs))
    return out


def _run_one(args):
    spec, out_dir, plots = args
    result = BatchRun(spec).run(progress=False)
    metrics = result.write(Path(out_dir) / spec.label, plots=plots)
    return spec.label, metrics


def run_experiment(name: str, seeds: Sequence[int], feedback: str, out, jobs: int = 1, plots: bool = True,
                   progress: bool = True, starts: Optional[Sequence[int]] = None, **spec_kwargs) -> Dict[str, Any]:
    """Runs every (seed, start) of an experiment with one feedback; writes the runs and the summary
    into out/<feedback>/. Returns the summary (see summarise)."""
    out_dir = Path(out) / feedback
    out_dir.mkdir(parents=True, exist_ok=True)
    specs = runs_of(name, seeds, feedback, starts=starts, **spec_kwargs)
    work = [(s, out_dir, plots) for s in specs]
    results = []
    t0 = time.perf_counter()
    bar = None
    if progress:
        bar = tqdm(total=len(work), desc=f"{name} {feedback}", unit="run", dynamic_ncols=True, file=sys.stderr)
    if jobs > 1:
        with get_context("fork").Pool(jobs) as pool:
            for label, metrics in pool.imap_unordered(_run_one, work):
                results.append((label, metrics))
                _report_line(bar, label, metrics)
    else:
        for item in work:
            label, metrics = _run_one(item)
            results.append((label, metrics))
            _report_line(bar, label, metrics)
    if bar is not None:
        bar.close()
    results.sort(key=lambda r: r[0])
    summary = summarise(name, feedback, results, time.perf_counter() - t0)
    write_summary(out_dir, summary, results, plots=plots)
    return summary


def _report_line(bar, label, m):
    wps = m["waypoints"]
    line = (f"{label}: {m['waypoints_reached']}/{len(wps)} waypoints, "
            f"{m['mission_time_s']:.0f} s simulated ({m['outcome']})"
            + (", ROLLED OVER" if m["rolled_over"] else "")
            + (f", {m['limit_violations']} limit violations" if m["limit_violations"] else ""))
    if bar is None:
        print(line, flush=True)
    else:
        bar.write(line)
        bar.update(1)


def run_success(m: Dict[str, Any]) -> bool:
    return (bool(m["all_reached"]) and not m["rolled_over"] and m["limit_violations"] == 0
            and bool(m.get("recovered_all", True)))


def _stats(values) -> Dict[str, Optional[float]]:
    v = np.asarray([x for x in values if x is not None], float)
    if not len(v):
        return {"median": None, "max": None, "n": 0}
    return {"median": float(np.median(v)), "max": float(np.max(v)), "n": int(len(v))}


def summarise(name: str, feedback: str, results, wall_s: float) -> Dict[str, Any]:
    ms = [m for _, m in results]
    wps = [w for m in ms for w in m["waypoints"]]
    dist = [m.get("disturbances", []) for m in ms]
    flat = [d for ds in dist for d in ds]
    sim_total = sum(m["sim_time_s"] for m in ms)
    return {
        "experiment": name, "feedback": feedback, "runs": len(ms),
        "successes": int(sum(run_success(m) for m in ms)),
        "accepted": bool(ms) and all(run_success(m) for m in ms),
        "waypoints": len(wps), "waypoints_reached": int(sum(w["reached"] for w in wps)),
        "time_per_waypoint_s": _stats(w["time_s"] for w in wps),
        "final_distance_m": _stats(w["final_distance_m"] for w in wps if w["reached"]),
        "final_yaw_error_deg": _stats(abs(w["final_yaw_error_deg"]) for w in wps
                                      if w["reached"] and w["final_yaw_error_deg"] is not None),
        "final_heading_error_deg": _stats(abs(w["final_yaw_error_abs_deg"]) for w in wps
                                          if w["reached"] and w["final_yaw_error_abs_deg"] is not None),
        "true_final_distance_m": _stats(w.get("true_final_distance_m") for w in wps if w["reached"]),
        "true_final_heading_error_deg": _stats(abs(w["true_final_yaw_error_abs_deg"]) for w in wps
                                               if w["reached"] and w.get("true_final_yaw_error_abs_deg") is not None),
        "rolled_over": int(sum(m["rolled_over"] for m in ms)),
        "max_tilt_deg": max((m["max_tilt_deg"] for m in ms), default=None),
        "limit_violations": int(sum(m["limit_violations"] for m in ms)),
        "disturbances": len(flat), "disturbances_recovered": int(sum(d["recovered"] for d in flat)),
        "time_to_recover_s": _stats(d["time_to_recover_s"] for d in flat),
        "vio_ape_rmse_m": _stats((m.get("vio_evaluation") or {}).get("ape_translation_m", {}).get("rmse")
                                 for m in ms),
        "simulated_s": sim_total, "wall_s": wall_s,
        "failed_runs": [label for label, m in results if not run_success(m)],
    }


def _fmt(s: Dict[str, Optional[float]], digits: int = 1) -> str:
    if s["median"] is None:
        return "-"
    return f"{s['median']:.{digits}f} / {s['max']:.{digits}f}"


TABLE_HEADER = ("| experiment | feedback | successful runs | waypoints reached | time per waypoint (s) median / worst "
                "| final distance (m) median / worst | final yaw error (deg) median / worst | true final distance (m) "
                "| roll-overs | limit violations | disturbances recovered |")


TABLE_RULE = "|" + "---|" * (TABLE_HEADER.count("|") - 1)


def table_row(s: Dict[str, Any]) -> str:
    dist = f"{s['disturbances_recovered']}/{s['disturbances']}" if s["disturbances"] else "-"
    return (f"| {s['experiment']} | {s['feedback']} | {s['successes']}/{s['runs']} | "
            f"{s['waypoints_reached']}/{s['waypoints']} | {_fmt(s['time_per_waypoint_s'], 0)} | "
            f"{_fmt(s['final_distance_m'], 2)} | {_fmt(s['final_yaw_error_deg'])} | "
            f"{_fmt(s['true_final_distance_m'], 2)} | {s['rolled_over']} | {s['limit_violations']} | {dist} |")


def write_summary(out_dir: Path, summary: Dict[str, Any], results, plots: bool = True) -> None:
    write_json_atomic(out_dir / "summary.json", {**summary, "runs_detail": [
        {"label": label, "outcome": m["outcome"], "success": run_success(m), "start": m.get("start"),
         "seed": m.get("seed"), "mission_time_s": m["mission_time_s"],
         "time_per_waypoint_s": [w["time_s"] for w in m["waypoints"]]} for label, m in results]})
    lines = [f"# {summary['experiment']} with {summary['feedback']} feedback", "",
             "Time per waypoint: from the previous waypoint (or the start) to this one. Final distance and yaw "
             "error: the tracker's own (combined error of Algorithm 1 line 8) at the step the waypoint was "
             "reached; true final distance: the same from the simulator's ground truth.", "",
             TABLE_HEADER, TABLE_RULE,
             table_row(summary), ""]
    if summary["failed_runs"]:
        lines.append("Failed runs: " + ", ".join(summary["failed_runs"]))
    lines.append(f"{summary['simulated_s']:.0f} s simulated in {summary['wall_s']:.0f} s of wall-clock time.")
    (out_dir / "summary.md").write_text("\n".join(lines) + "\n")
    if plots:
        summary_figure(out_dir, summary, results)


def summary_figure(out_dir: Path, summary, results) -> Path:
    plt = _pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 6), gridspec_kw={"width_ratios": [1.2, 1]})
    cmap = plt.get_cmap("tab10")
    waypoints = None
    labelled = set()
    for label, m in results:
        traj = out_dir / label / "trajectory.csv"
        if not traj.is_file():
            continue
        data = np.genfromtxt(traj, delimiter=",", names=True)
        seed = m.get("seed", 0) or 0
        ax.plot(data["x_true"], data["y_true"], "-", lw=0.8, alpha=0.8, color=cmap(seed % 10),
                label=None if seed in labelled else f"seed {seed}")
        labelled.add(seed)
        ax.plot(data["x_true"][0], data["y_true"][0], "o", ms=3, color=cmap(seed % 10))
        for d in m.get("disturbances", []):
            t = d["t_s"]
            i = int(np.searchsorted(data["t"], t))
            if i < len(data["t"]):
                ax.plot(data["x_true"][i], data["y_true"][i], "x", color="red", ms=7)
        waypoints = waypoints or [(w["x_m"], w["y_m"], math.radians(w["heading_deg"])) for w in m["waypoints"]]
    for i, (x, y, h) in enumerate(waypoints or []):
        ax.add_patch(plt.Circle((x, y), 0.35, fill=False, ls="--", color="grey", lw=0.8))
        ax.arrow(x, y, 0.3 * math.cos(h), 0.3 * math.sin(h), width=0.012, head_width=0.07, color="black",
                 length_includes_head=True, zorder=5)
        ax.annotate(f"WP{i}", (x, y), textcoords="offset points", xytext=(6, 6), fontsize=8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, lw=0.3)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{summary['experiment']} ({summary['feedback']}): centre of mass, ground truth"
                 + (" (x: disturbances)" if summary["disturbances"] else ""))
    ax.legend(fontsize=7, loc="best")
    n_wp = max((len(m["waypoints"]) for _, m in results), default=0)
    data = [[m["waypoints"][k]["time_s"] for _, m in results
             if k < len(m["waypoints"]) and m["waypoints"][k]["time_s"] is not None] for k in range(n_wp)]
    if any(data):
        bx.boxplot([d if d else [np.nan] for d in data])
        bx.set_xticks(range(1, n_wp + 1), [f"WP{k}" for k in range(n_wp)])
        for k, d in enumerate(data):
            bx.plot(np.full(len(d), k + 1) + np.random.default_rng(k).uniform(-0.15, 0.15, len(d)), d, ".",
                    ms=4, alpha=0.6, color="tab:blue")
    bx.set_ylabel("time for the waypoint (s)")
    bx.set_title(f"{summary['successes']}/{summary['runs']} runs successful, "
                 f"{summary['waypoints_reached']}/{summary['waypoints']} waypoints reached")
    bx.grid(True, lw=0.3, axis="y")
    path = out_dir / "summary.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def parse_seeds(text: str) -> List[int]:
    """'0-4' or '0,2,5' or '3'."""
    out = []
    for part in str(text).split(","):
        part = part.strip()
        if "-" in part[1:]:
            a, b = part.split("-", 1)
            out.extend(range(int(a), int(b) + 1))
        elif part:
            out.append(int(part))
    if not out:
        raise ValueError(f"seeds: expected e.g. 0-4 or 0,2,5, got {text!r}")
    return out


def default_jobs() -> int:
    return max(1, min(2, (os.cpu_count() or 1)))
