"""Outputs of one evaluation: the statistics table, the JSON, the plots and a one-page report.

``write_outputs(result, out_dir)`` writes all of them into one folder (what the simulator puts in a
run's results folder): ``stats.json``, ``xy.png``, ``xyz.png``, ``axis_error.png`` (APE),
``error.png``, ``report.pdf`` and ``report.png`` (the same single page).
"""
import json
from pathlib import Path
from typing import Dict, Optional

from . import plots
from . import plots as plots_mod
from .stats import STAT_KEYS


def format_table(result) -> str:
    """evo's statistics table (same order and precision), then pairs, loss and segments."""
    lines = [result.title, ""]
    for key in STAT_KEYS:
        lines.append(f"{key:>10}\t{result.stats[key]:.6f}")
    lines.append("")
    lines.append(f"{'pairs':>10}\t{result.pairs}" + (f" ({result.excluded_pairs} excluded: tracking loss)"
                                                       if result.excluded_pairs else ""))
    if result.loss_intervals:
        total = sum(iv.duration_s for iv in result.loss_intervals)
        lines.append(f"{'loss':>10}\t{len(result.loss_intervals)} intervals, {total:.2f} s")
    for key, groups in result.segments.items():
        lines.append("")
        lines.append(segment_table(key, groups, result.unit))
    return "\n".join(lines)


def segment_table(key: str, groups, unit: str) -> str:
    width = max([len(key)] + [len(g["label"]) for g in groups])
    head = f"{key:<{width}}  {'pairs':>6}  {'max':>9}  {'mean':>9}  {'rmse':>9}   ({unit})"
    rows = [head]
    for g in groups:
        s = g["stats"]
        rows.append(f"{g['label']:<{width}}  {g['pairs']:>6}  {s['max']:>9.4f}  {s['mean']:>9.4f}  "
                    f"{s['rmse']:>9.4f}")
    return "\n".join(rows)


def write_json(result, path) -> str:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result.to_dict(), indent=2, default=_json_default) + "\n")
    return str(path)


def _json_default(obj):
    if hasattr(obj, "tolist"):
        return obj.tolist()
    if hasattr(obj, "item"):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def write_report(result, out_dir, name: str = "report") -> Dict[str, str]:
    """One A4-landscape page: statistics, segments and the four plots; as PDF and PNG."""
    import matplotlib  # lazy: matplotlib is heavy and only this path needs it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fig = plt.figure(figsize=(11.69, 8.27))
    grid = fig.add_gridspec(3, 3, width_ratios=[1.3, 1.2, 1.2], hspace=0.45, wspace=0.3,
                            left=0.04, right=0.98, top=0.93, bottom=0.07)
    fig.suptitle(f"{result.options.metric.upper()}: {result.est_name} vs {result.ref_name}", fontsize=11)
    text_ax = fig.add_subplot(grid[:, 0])
    text_ax.axis("off")
    text_ax.text(0.0, 1.0, _summary_text(result), va="top", ha="left", family="monospace", fontsize=7,
                 transform=text_ax.transAxes)
    plots.plot_xy(fig.add_subplot(grid[0:2, 1]), result)
    xyz_grid = grid[0:2, 2].subgridspec(3, 1, hspace=0.1)
    xyz_axes = [fig.add_subplot(xyz_grid[0])]
    xyz_axes += [fig.add_subplot(xyz_grid[k], sharex=xyz_axes[0]) for k in (1, 2)]
    plots.plot_xyz(xyz_axes, result)
    for ax in xyz_axes[:-1]:
        ax.tick_params(labelbottom=False)
    plots.plot_error(fig.add_subplot(grid[2, 1]), result)
    if result.options.metric == "ape":
        plots.plot_axis_error(fig.add_subplot(grid[2, 2]), result)
    paths = {}
    for ext in ("pdf", "png"):
        path = out / f"{name}.{ext}"
        fig.savefig(path, dpi=100)
        paths[f"{name}_{ext}"] = str(path)
    plt.close(fig)
    return paths


def _summary_text(result) -> str:
    o = result.options
    lines = [format_table(result).expandtabs(12), "", "options:",
             f"  align {o.align}, relation {o.relation}",
             f"  t_max_diff {o.t_max_diff_s:g} s, t_offset {o.t_offset_s:g} s, sync {o.sync}"]
    if o.metric == "rpe":
        lines.append(f"  delta {o.delta:g} {o.delta_unit}{', all pairs' if o.all_pairs else ''}")
    gap = "auto" if o.max_gap_s is None else f"{o.max_gap_s:g} s"
    lines.append(f"  max_gap {gap}, loss {'excluded' if o.exclude_loss else 'kept'}")
    if result.alignment is not None:
        d = result.to_dict()
        lines.append(f"  alignment: yaw {d['alignment_yaw_deg']:.2f} deg, scale {d['alignment_scale']:.4f}")
    for iv in result.loss_intervals[:12]:
        lines.append(f"  loss {iv.kind:<10} {iv.start_s - result.traj_est.timestamps[0]:9.2f} s "
                     f"+{iv.duration_s:.2f} s")
    if len(result.loss_intervals) > 12:
        lines.append(f"  ... {len(result.loss_intervals) - 12} more in stats.json")
    return "\n".join(lines)


def write_outputs(result, out_dir, plots: bool = True, report: bool = True,
                  json_path: Optional[str] = None) -> Dict[str, str]:
    """Writes stats.json (or json_path), the PNG plots and the one-page report; returns {name: path}."""

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"json": write_json(result, json_path or out / "stats.json")}
    if plots:
        paths.update(plots_mod.save_figures(result, out))
    if report:
        paths.update(write_report(result, out))
    return paths
