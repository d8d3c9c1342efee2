"""What a calibration writes: a YAML the tracker reads (never applied by itself) and the figure.

calibration.yaml has two sections:
- `tracker:` delta0_deg (eq. 3.31's δ_offset: Algorithm 1's δ0) and heading_offset_deg, in the
  shape of config/sim.yaml's `tracker:` section: the mission node reads it as ~tracker_overrides
  (`roslaunch snake_autonomy mission.launch tracker_overrides:=.../calibration.yaml`), or merge the
  two keys into config/sim.yaml's `tracker:` (the simulated robot) or config/tracker.yaml (the robot);
- `calibration:` the evidence (fit, scatter, every segment), read by nobody.
calibration.png: turn rate against δ (the fit of eq. 3.31 and its scatter) and the heading offset.
"""
import datetime
from dataclasses import asdict
from pathlib import Path
from typing import Dict

import numpy as np
import yaml

from .analysis import CalibrationResult


def tracker_block(result: CalibrationResult) -> Dict[str, float]:
    return {"delta0_deg": round(result.delta_offset_deg, 1), "heading_offset_deg": round(result.heading_offset_deg, 1)}


def write_yaml(path, result: CalibrationResult, source: Dict) -> Path:
    """calibration.yaml: `tracker:` (what to use) and `calibration:` (how it was measured)."""
    path = Path(path)
    r = result
    evidence = {
        **source,
        "method": ("thesis eq. 3.31: delta_offset = -K_bias * drift rate at delta 0, "
                   "K_bias = 1 / (d turn rate / d delta)"),
        "delta_offset_deg": r.delta_offset_deg, "delta_offset_std_deg": r.delta_offset_std_deg,
        "drift_rate_deg_s": r.drift_rate_deg_s, "steering_gain_deg_s_per_deg": r.steering_gain_deg_s_per_deg,
        "k_bias_s": r.k_bias_s, "rate_residual_std_deg_s": r.rate_residual_std_deg_s,
        "heading_offset_deg": r.heading_offset_deg, "heading_offset_per_deg_delta": r.heading_offset_slope,
        "heading_offset_residual_std_deg": r.heading_offset_residual_std_deg,
        "per_run_delta_offset_deg": dict(r.per_run_delta_offset_deg),
        "warnings": list(r.warnings),
        "segments": [asdict(s) for s in r.segments],
    }
    header = (f"# snake_autonomy calibrate, {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC.\n"
              "# Not applied by itself. Use the tracker: block as the mission node's ~tracker_overrides\n"
              "# (mission.launch tracker_overrides:=THIS_FILE) or merge its keys into config/sim.yaml's tracker:\n"
              "# (the simulated robot) or config/tracker.yaml (the robot).\n")
    body = yaml.safe_dump({"tracker": tracker_block(r), "calibration": _plain(evidence)}, sort_keys=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(header + body)
    return path


def plot(path, result: CalibrationResult, title: str = "") -> Path:
    import matplotlib  # lazy: matplotlib is heavy and only this path needs it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = result
    segs = r.segments
    d = np.array([s.delta_deg for s in segs])
    span = np.linspace(min(d.min(), r.delta_offset_deg) - 0.5, max(d.max(), r.delta_offset_deg) + 0.5, 50)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    runs = sorted({s.run for s in segs})
    for run in runs:
        mine = [s for s in segs if s.run == run]
        ax1.plot([s.delta_deg for s in mine], [s.turn_rate_deg_s for s in mine], "o", label=run or "run")
        ax2.plot([s.delta_deg for s in mine], [s.heading_offset_deg for s in mine], "o", label=run or "run")
    ax1.plot(span, r.drift_rate_deg_s + r.steering_gain_deg_s_per_deg * span, "k-",
             label=f"fit: {r.drift_rate_deg_s:+.2f} {r.steering_gain_deg_s_per_deg:+.3f} δ "
                   f"({r.spread(r.rate_residual_std_deg_s, sign='±')})")
    ax1.axhline(0.0, color="grey", lw=0.8)
    ax1.axvline(r.delta_offset_deg, color="tab:red", ls="--",
                label=f"δ_offset = {r.delta_offset_deg:+.2f}° ({r.spread(r.delta_offset_std_deg, sign='±')})")
    ax1.set(xlabel="steering δ (deg)", ylabel="turn rate (deg/s)", title="eq. 3.31: heading drift vs δ")
    ax2.plot(span, r.heading_offset_deg + r.heading_offset_slope * (span - r.delta_offset_deg), "k-",
             label=f"fit ({r.spread(r.heading_offset_residual_std_deg, '.1f', '°', '±')})")
    ax2.axvline(r.delta_offset_deg, color="tab:red", ls="--",
                label=f"heading offset {r.heading_offset_deg:+.1f}° at δ_offset")
    ax2.set(xlabel="steering δ (deg)", ylabel="travel − chassis x axis (deg)", title="heading offset")
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _plain(value):
    """numpy scalars and tuples to plain YAML types."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return round(float(value), 4)
    if isinstance(value, np.integer):
        return int(value)
    return value
