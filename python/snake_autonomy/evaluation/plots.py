"""Figures of one evaluation (matplotlib, Agg): each draws into axes it is given, so the one-page
report reuses them.

- xy: reference and aligned estimate in the XY plane, where tracking was lost marked (thesis Fig. 4.4);
- xyz: x, y, z of both over time (thesis Fig. 4.5), tracking loss shaded;
- axis error: estimate minus reference per axis over time (APE only);
- error: the metric's error over time, rmse/mean lines, tracking loss shaded red, segments (legs)
  shaded alternately as in the thesis's Fig. 4.16.
Time axes are seconds from the first associated estimate stamp.
"""
from pathlib import Path

import numpy as np

from .tracking_loss import spans_in_loss

LOSS_COLOR = "tab:red"
REF_STYLE = dict(color="0.35", linestyle="--", linewidth=1.2, label="reference")
EST_STYLE = dict(color="tab:blue", linewidth=1.2)


def est_label(result) -> str:
    return "estimate" if result.options.align == "none" else f"estimate ({result.options.align}-aligned)"


def break_at_loss(t_s: np.ndarray, values: np.ndarray, result) -> tuple:
    """(t, values) with a NaN row between consecutive samples that span a loss interval, so that
    lines are not drawn across it. t_s are absolute stamps (estimate time)."""
    t_s = np.asarray(t_s, dtype=float)
    values = np.asarray(values, dtype=float)
    if len(t_s) < 2 or not result.loss_intervals:
        return t_s, values
    cut = np.nonzero(spans_in_loss(t_s[:-1], t_s[1:], result.loss_intervals))[0] + 1
    nan_row = np.full((len(cut),) + values.shape[1:], np.nan)
    return np.insert(t_s, cut, np.nan), np.insert(values, cut, nan_row, axis=0)


def time_origin(result) -> float:
    return float(result.traj_est.timestamps[0])


def shade_loss(ax, result, t0: float, label: bool = True) -> None:
    first = True
    for iv in result.loss_intervals:
        start, end = iv.start_s - t0, iv.end_s - t0
        if end <= start:  # a single lost sample at an end of the data: draw a line
            ax.axvline(start, color=LOSS_COLOR, alpha=0.4)
        else:
            ax.axvspan(start, end, color=LOSS_COLOR, alpha=0.18, linewidth=0,
                       label="tracking loss" if (label and first) else None)
        first = False


def shade_segments(ax, result, t0: float, key: str = "leg") -> None:
    spans = result.segment_spans.get(key) or []
    for k, (start, end, label) in enumerate(spans):
        if k % 2:
            ax.axvspan(start - t0, end - t0, color="0.9", linewidth=0, zorder=0)
        ax.text(start - t0, 1.0, f" {label}", transform=ax.get_xaxis_transform(), fontsize=6,
                va="top", ha="left", color="0.3", rotation=90, clip_on=True)


def full_estimate_xyz(result) -> np.ndarray:
    """All associated estimate positions after alignment (already applied to traj_est)."""
    return np.asarray(result.traj_est.positions_xyz)


def plot_xy(ax, result) -> None:
    ref_full = result.traj_ref_full if result.traj_ref_full is not None else result.traj_ref
    ref = np.asarray(ref_full.positions_xyz)
    est = full_estimate_xyz(result)
    ax.plot(ref[:, 0], ref[:, 1], **REF_STYLE)
    _, est_xy = break_at_loss(result.traj_est.timestamps, est[:, :2], result)
    ax.plot(est_xy[:, 0], est_xy[:, 1], label=est_label(result), **EST_STYLE)
    ax.plot(est[0, 0], est[0, 1], "o", color="tab:green", markersize=4, label="start")
    if result.loss_intervals:
        stamps = np.asarray(ref_full.timestamps, dtype=float) - result.options.t_offset_s
        idx = np.clip(np.searchsorted(stamps, [iv.start_s for iv in result.loss_intervals]), 0, len(ref) - 1)
        ax.plot(ref[idx, 0], ref[idx, 1], "x", color=LOSS_COLOR, markersize=7, label="tracking lost")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title("XY trajectory")


def plot_xyz(axes, result) -> None:
    t0 = time_origin(result)
    ref_full = result.traj_ref_full if result.traj_ref_full is not None else result.traj_ref
    t_ref = np.asarray(ref_full.timestamps, dtype=float) - result.options.t_offset_s - t0
    ref = np.asarray(ref_full.positions_xyz)
    t, est = break_at_loss(result.traj_est.timestamps, result.traj_est.positions_xyz, result)
    t = t - t0
    for k, (ax, name) in enumerate(zip(axes, "xyz")):
        ax.plot(t_ref, ref[:, k], **REF_STYLE)
        ax.plot(t, est[:, k], label=est_label(result), **EST_STYLE)
        shade_loss(ax, result, t0, label=(k == 0))
        ax.set_ylabel(f"{name} (m)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7, loc="best")
    axes[0].set_title("position over time")
    axes[-1].set_xlabel("t (s)")


def plot_axis_error(ax, result) -> None:
    t0 = time_origin(result)
    diff = np.asarray(result.traj_est.positions_xyz) - np.asarray(result.traj_ref.positions_xyz)
    t, diff = break_at_loss(result.traj_est.timestamps, diff, result)
    t = t - t0
    for k, (name, color) in enumerate(zip("xyz", ("tab:red", "tab:green", "tab:blue"))):
        ax.plot(t, diff[:, k], color=color, linewidth=1.0, label=f"{name} error")
    shade_loss(ax, result, t0, label=False)
    ax.axhline(0.0, color="0.5", linewidth=0.8)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("estimate - reference (m)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title("per-axis position error")


def plot_error(ax, result, segment_key: str = "leg") -> None:
    t0 = time_origin(result)
    t, errors = break_at_loss(result.stamps_s, result.errors, result)
    t = t - t0
    shade_segments(ax, result, t0, segment_key)
    ax.plot(t, errors, color="tab:blue", linewidth=1.0, label=result.options.metric.upper())
    ax.axhline(result.stats["rmse"], color="tab:orange", linewidth=1.0, label=f"rmse {result.stats['rmse']:.4g}")
    ax.axhline(result.stats["mean"], color="tab:purple", linewidth=1.0, linestyle=":",
               label=f"mean {result.stats['mean']:.4g}")
    shade_loss(ax, result, t0)
    ax.set_xlabel("t (s)")
    ax.set_ylabel(f"{result.options.metric.upper()} ({result.unit})")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title("error over time")


def save_figures(result, out_dir) -> dict:
    """Writes xy.png, xyz.png, error.png (and axis_error.png for APE); returns {name: path}."""
    import matplotlib  # lazy: matplotlib is heavy and only this path needs it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {}

    def save(name, fig):
        path = out / f"{name}.png"
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths[name] = str(path)

    fig, ax = plt.subplots(figsize=(6, 5))
    plot_xy(ax, result)
    save("xy", fig)
    fig, axes = plt.subplots(3, 1, figsize=(8, 6), sharex=True)
    plot_xyz(axes, result)
    save("xyz", fig)
    if result.options.metric == "ape":
        fig, ax = plt.subplots(figsize=(8, 3.5))
        plot_axis_error(ax, result)
        save("axis_error", fig)
    fig, ax = plt.subplots(figsize=(8, 3.5))
    plot_error(ax, result)
    save("error", fig)
    return paths
