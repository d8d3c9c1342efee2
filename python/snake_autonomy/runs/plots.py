"""The figures of a run (matplotlib, Agg backend: no display needed)."""
import math
from pathlib import Path
from typing import Dict, List, Mapping

import numpy as np

DEG = 180.0 / math.pi


def _pyplot():
    import matplotlib  # lazy: matplotlib is heavy and only drawing needs it
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


def segments(decisions: Mapping[str, np.ndarray]) -> List[Dict[str, float]]:
    """Time spans during which each waypoint was the target: [{index, t_start, t_end}]."""
    d = decisions
    out: List[Dict[str, float]] = []
    for t, k in zip(d["t"], d["target_index"]):
        if out and out[-1]["index"] == k:
            out[-1]["t_end"] = float(t)
        else:
            if out:
                out[-1]["t_end"] = float(t)
            out.append({"index": int(k), "t_start": float(t), "t_end": float(t)})
    return out


def _shade_segments(ax, dec, t0):
    colours = ["#dbe9f6", "#fde5cc"]
    for n, seg in enumerate(segments(dec)):
        a, b = seg["t_start"] - t0, seg["t_end"] - t0
        ax.axvspan(a, b if b > a else a + 0.5, color=colours[n % 2], alpha=0.8, lw=0, zorder=0)
        ax.text((a + b) / 2, 1.0, f"WP{seg['index']}", transform=ax.get_xaxis_transform(), ha="center",
                va="bottom", fontsize=7)


def _save_over_time(plt, fig, ax, ylabel: str, title: str, path: Path) -> Path:
    """Labels, grid and legend of a plot over time; saves it to PATH and closes it."""
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title, pad=14)
    ax.grid(True, lw=0.3)
    ax.legend(loc="upper right", fontsize=8)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_all(out: Path, waypoints, traj, dec, t0: float, d_th: float, psi_wp: float, psi_turn: float,
             title: str = "") -> Dict[str, Path]:
    plt = _pyplot()
    paths = {}
    suffix = f" - {title}" if title else ""

    # XY trajectory with the waypoints (thesis fig. 4.10)
    fig, ax = plt.subplots(figsize=(6.5, 6))
    if "x_true" in traj and len(traj["x_true"]):
        ax.plot(traj["x_true"], traj["y_true"], "--", color="tab:grey", lw=1.0, label="ground truth")
    if len(traj["x"]):
        ax.plot(traj["x"], traj["y"], "-", color="tab:blue", lw=1.2, label="centre of mass")
        ax.plot(traj["x"][0], traj["y"][0], "o", color="tab:green", label="start")
        ax.plot(traj["x"][-1], traj["y"][-1], "s", color="tab:red", label="end")
    for i, (x, y, h) in enumerate(waypoints):
        ax.add_patch(plt.Circle((x, y), d_th, fill=False, ls="--", color="grey", lw=0.8))
        ax.arrow(x, y, 0.25 * math.cos(h), 0.25 * math.sin(h), width=0.01, head_width=0.06,
                 color="black", length_includes_head=True)
        ax.annotate(f"WP{i}", (x, y), textcoords="offset points", xytext=(6, 6), fontsize=8)
    if len(waypoints):
        ax.plot([w[0] for w in waypoints], [w[1] for w in waypoints], "k*", ms=9, label="waypoints")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("Trajectory" + suffix)
    ax.grid(True, lw=0.3)
    ax.legend(loc="best", fontsize=8)
    paths["trajectory_png"] = out / "trajectory.png"
    fig.savefig(paths["trajectory_png"], dpi=120, bbox_inches="tight")
    plt.close(fig)

    t = dec["t"] - t0
    # distance error over time
    fig, ax = plt.subplots(figsize=(8, 3.5))
    _shade_segments(ax, dec, t0)
    ax.plot(t, dec["distance"], "-o", ms=2, color="tab:blue", label="distance error")
    ax.axhline(d_th, ls="--", color="grey", lw=0.8, label=f"d_th = {d_th:.2f} m")
    paths["distance_png"] = _save_over_time(plt, fig, ax, "distance to waypoint (m)", "Distance error" + suffix,
                                            out / "distance_error.png")

    # yaw errors over time
    fig, ax = plt.subplots(figsize=(8, 3.5))
    _shade_segments(ax, dec, t0)
    ax.plot(t, dec["yaw_error_abs"] * DEG, "-", lw=1, color="tab:orange", label="absolute")
    ax.plot(t, dec["yaw_error_rel"] * DEG, "-", lw=1, color="tab:green", label="relative")
    ax.plot(t, dec["yaw_error"] * DEG, "-", lw=1.8, color="tab:blue", label="combined")
    for v in (psi_wp, psi_turn):
        ax.axhline(v * DEG, ls=":", color="grey", lw=0.8)
        ax.axhline(-v * DEG, ls=":", color="grey", lw=0.8)
    paths["yaw_png"] = _save_over_time(plt, fig, ax, "yaw error (deg)", "Yaw errors" + suffix,
                                       out / "yaw_errors.png")

    # combined yaw error against distance (thesis figs. 4.16-4.20)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    cmap = plt.get_cmap("tab10")
    for k in sorted(set(int(v) for v in dec["target_index"])):
        m = dec["target_index"] == k
        ax.plot(dec["distance"][m], dec["yaw_error"][m] * DEG, "-o", ms=3, lw=0.8, color=cmap(k % 10),
                label=f"WP{k}")
    ax.axvline(d_th, ls="--", color="grey", lw=0.8)
    for v in (psi_wp, -psi_wp):
        ax.axhline(v * DEG, ls=":", color="grey", lw=0.8)
    ax.invert_xaxis()
    ax.set_xlabel("distance to waypoint (m)")
    ax.set_ylabel("combined yaw error (deg)")
    ax.set_title("Combined yaw error vs distance" + suffix)
    ax.grid(True, lw=0.3)
    if len(dec["t"]):
        ax.legend(loc="best", fontsize=8)
    paths["yaw_vs_distance_png"] = out / "yaw_error_vs_distance.png"
    fig.savefig(paths["yaw_vs_distance_png"], dpi=120, bbox_inches="tight")
    plt.close(fig)
    return paths
