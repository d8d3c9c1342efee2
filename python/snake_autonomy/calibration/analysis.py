"""The steering calibration's analysis (thesis 3.6.4, eq. 3.31): pure numpy, one for both back-ends.

    seg = Segment(delta_deg=2.0, period_s=2.857, samples=np.array([[t, x, y, yaw], ...]), run="seed 0")
    result = fit([seg, ...])
    result.delta_offset_deg, result.heading_offset_deg

Input: open-loop sidewinding at a few steering values δ (Algorithm 1's δ, the amplitude modulation
of eq. 3.26-3.29), each a Segment of com_pose samples (time s, centre of mass x, y in m, virtual
chassis yaw in rad, as the driver publishes it) over whole gait cycles after settling.

Per segment:
- turn rate θ̇ (deg/s): least-squares slope of the unwrapped chassis yaw over time, on its
  per-cycle averages (the gait's oscillation of the chassis cancels over a whole cycle);
- heading offset (deg): per gait cycle, the direction of the CoM's displacement over the cycle minus
  the chassis yaw averaged over the cycle, then averaged over cycles (circular means): where the
  robot goes relative to the virtual chassis x axis, the tracker's heading_offset_deg.

Across segments (every run pooled), θ̇ = θ̇_drift + k δ is fitted by least squares. Eq. 3.31,
δ_offset = -K_bias <θ̇_drift>, with the drift rate at δ = 0 and K_bias = 1/k (s): the δ that sidewinds
straight, which is Algorithm 1's δ0 (config/tracker.yaml delta0_deg). The heading offset is fitted
linearly in δ too and read at δ_offset. The scatter: residual standard deviations of both fits, δ's
from the drift fit's standard errors, and each run's own δ_offset when a run has two δ values or more.
"""
import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

DEG = 180.0 / math.pi


class CalibrationError(ValueError):
    """The data cannot give a calibration (too few segments or cycles, steering without effect)."""


@dataclass
class Segment:
    delta_deg: float              # the commanded steering δ
    period_s: float               # the gait's period (1 / frequency)
    samples: np.ndarray           # (n, 4): t_s, x_m, y_m, yaw_rad (com_pose: CoM and chassis yaw)
    run: str = ""                 # which run (seed, robot session): per-run fits


@dataclass
class SegmentFigures:
    delta_deg: float
    run: str
    turn_rate_deg_s: float
    heading_offset_deg: float
    cycles: int
    duration_s: float
    distance_m: float


@dataclass
class CalibrationResult:
    delta_offset_deg: float               # eq. 3.31: straight sidewinding (Algorithm 1's δ0)
    heading_offset_deg: float             # direction of travel - virtual chassis x axis, at δ_offset
    drift_rate_deg_s: float               # <θ̇_drift>: the turn rate at δ = 0
    steering_gain_deg_s_per_deg: float    # k = dθ̇/dδ
    k_bias_s: float                       # K_bias = 1 / k
    rate_residual_std_deg_s: float        # scatter of the turn rates about the line
    delta_offset_std_deg: float           # standard error of δ_offset (from the line's)
    heading_offset_slope: float           # heading offset per degree of δ
    heading_offset_residual_std_deg: float
    segments: List[SegmentFigures]
    per_run_delta_offset_deg: Dict[str, float] = field(default_factory=dict)
    warnings: List[str] = field(default_factory=list)

    def spread(self, value: float, fmt: str = ".2f", unit: str = "", sign: str = "+-") -> str:
        """A scatter figure as text: "+-0.12" + unit, or why there is none (a line through two
        segments says nothing of the scatter: its residual is NaN), never "nan"."""
        if math.isfinite(value):
            return f"{sign}{value:{fmt}}{unit}"
        return f"no spread with {len(self.segments)} segments (3 or more needed)"

    def summary(self) -> str:
        rate_scatter = self.spread(self.rate_residual_std_deg_s, unit=" deg/s", sign="")
        heading_scatter = self.spread(self.heading_offset_residual_std_deg, ".1f", " deg", "")
        lines = [f"delta_offset (eq. 3.31) = -K_bias * drift = -({self.k_bias_s:.3f} s) * "
                 f"({self.drift_rate_deg_s:+.2f} deg/s) = {self.delta_offset_deg:+.2f} deg "
                 f"({self.spread(self.delta_offset_std_deg)}); steering {self.steering_gain_deg_s_per_deg:+.3f} "
                 f"deg/s per deg, turn-rate scatter: {rate_scatter}",
                 f"heading offset (travel - chassis x axis) at delta_offset = {self.heading_offset_deg:+.1f} deg "
                 f"(scatter: {heading_scatter})"]
        if len(self.per_run_delta_offset_deg) > 1:
            v = np.array(list(self.per_run_delta_offset_deg.values()))
            lines.append(f"per run: delta_offset median {np.median(v):+.2f} deg, "
                         f"range [{v.min():+.2f}, {v.max():+.2f}]")
        return "\n".join(lines + [f"warning: {w}" for w in self.warnings])


def circular_mean(angles_rad) -> float:
    a = np.asarray(angles_rad, float)
    return float(math.atan2(np.mean(np.sin(a)), np.mean(np.cos(a))))


def wrap(angle_rad):
    return (np.asarray(angle_rad, float) + math.pi) % (2 * math.pi) - math.pi


def _cycle_means(t: np.ndarray, values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Time average of `values` over each [edges[k], edges[k+1]] (linear interpolation, 200 points)."""
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        grid = np.linspace(a, b, 200)
        out.append(float(np.mean(np.interp(grid, t, values))))
    return np.array(out)


def _cycle_edges(t: np.ndarray, period_s: float) -> np.ndarray:
    return np.arange(t[0], t[-1] + 0.02 * period_s, period_s)     # a last cycle short by a sample counts


def turn_rate_deg_s(samples: np.ndarray, period_s: float) -> float:
    """Slope (deg/s) of the unwrapped yaw over time: least squares on the per-cycle means (the gait's
    oscillation of the chassis cancels over whole cycles), on the samples when under two cycles."""
    t, yaw = samples[:, 0], np.unwrap(samples[:, 3])
    edges = _cycle_edges(t, period_s)
    if len(edges) >= 3:
        t, yaw = 0.5 * (edges[:-1] + edges[1:]), _cycle_means(t, yaw, edges)
    return float(np.polyfit(t - t[0], yaw, 1)[0] * DEG)


def heading_offset_deg(samples: np.ndarray, period_s: float) -> Tuple[float, int]:
    """Circular mean over whole cycles of (direction of the CoM's displacement over the cycle - the
    chassis yaw averaged over the cycle), degrees; and the number of cycles with travel."""
    t = samples[:, 0]
    edges = _cycle_edges(t, period_s)
    if len(edges) < 2:
        return math.nan, 0
    x, y = np.interp(edges, t, samples[:, 1]), np.interp(edges, t, samples[:, 2])
    yaw = _cycle_means(t, np.unwrap(samples[:, 3]), edges)
    dx, dy = np.diff(x), np.diff(y)
    moved = np.hypot(dx, dy) > 1e-6
    if not moved.any():
        return math.nan, 0
    return circular_mean(np.arctan2(dy, dx)[moved] - yaw[moved]) * DEG, int(np.count_nonzero(moved))


def segment_figures(seg: Segment) -> SegmentFigures:
    s = np.asarray(seg.samples, float)
    if s.ndim != 2 or s.shape[1] != 4 or len(s) < 3:
        raise CalibrationError(f"segment at delta {seg.delta_deg:+g} deg ({seg.run}): expected (n >= 3, 4) samples, "
                               f"got shape {s.shape}")
    if not np.all(np.diff(s[:, 0]) > 0):
        raise CalibrationError(f"segment at delta {seg.delta_deg:+g} deg ({seg.run}): times must increase")
    offset, cycles = heading_offset_deg(s, seg.period_s)
    return SegmentFigures(delta_deg=float(seg.delta_deg), run=seg.run, turn_rate_deg_s=turn_rate_deg_s(s, seg.period_s),
                          heading_offset_deg=offset, cycles=cycles, duration_s=float(s[-1, 0] - s[0, 0]),
                          distance_m=float(math.hypot(s[-1, 1] - s[0, 1], s[-1, 2] - s[0, 2])))


def _line(x: np.ndarray, y: np.ndarray):
    """Least squares y = a + b x: (a, b, residual std, covariance of (a, b)); the last two are NaN
    with two points (a line through them says nothing of the scatter)."""
    A = np.column_stack([np.ones_like(x), x])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = y - A @ coef
    s2 = float(resid @ resid) / (len(x) - 2) if len(x) > 2 else math.nan
    cov = s2 * np.linalg.inv(A.T @ A)
    return float(coef[0]), float(coef[1]), math.sqrt(s2), cov


def _zero_crossing(figs: Sequence[SegmentFigures]) -> Optional[float]:
    deltas = np.array([f.delta_deg for f in figs])
    if len(np.unique(deltas)) < 2:
        return None
    a, b, _, _ = _line(deltas, np.array([f.turn_rate_deg_s for f in figs]))
    return -a / b if b != 0 else None


def fit(segments: Sequence[Segment], min_gain_deg_s_per_deg: float = 0.05) -> CalibrationResult:
    """Eq. 3.31 over every segment (all runs pooled); CalibrationError when it cannot."""
    figs = [segment_figures(s) for s in segments]
    deltas = np.array([f.delta_deg for f in figs])
    if len(np.unique(deltas)) < 2:
        raise CalibrationError(f"need at least two different delta values, got {sorted(set(deltas.tolist()))}")
    rates = np.array([f.turn_rate_deg_s for f in figs])
    drift, gain, rate_std, cov = _line(deltas, rates)
    if not abs(gain) >= min_gain_deg_s_per_deg:
        raise CalibrationError(f"steering has no measurable effect: {gain:+.3f} deg/s per degree of delta "
                               f"(|k| < {min_gain_deg_s_per_deg}); turn rates {np.round(rates, 2).tolist()} deg/s")
    k_bias = 1.0 / gain
    delta_offset = -k_bias * drift                                   # eq. 3.31
    # delta method: d(-a/b) = -da/b + a db/b^2
    grad = np.array([-1.0 / gain, drift / gain ** 2])
    delta_std = math.sqrt(max(0.0, float(grad @ cov @ grad))) if len(figs) > 2 else math.nan
    warnings = []
    if not deltas.min() <= delta_offset <= deltas.max():
        warnings.append(f"delta_offset {delta_offset:+.2f} deg lies outside the measured deltas "
                        f"[{deltas.min():+g}, {deltas.max():+g}]: extrapolated; measure around it")
    good = [f for f in figs if f.cycles > 0 and math.isfinite(f.heading_offset_deg)]
    if not good:
        raise CalibrationError("no whole gait cycle with travel in any segment: no heading offset")
    ref = circular_mean([f.heading_offset_deg / DEG for f in good])
    offs = np.array([ref + float(wrap(f.heading_offset_deg / DEG - ref)) for f in good]) * DEG
    d_good = np.array([f.delta_deg for f in good])
    if len(np.unique(d_good)) >= 2:
        h0, h_slope, h_std, _ = _line(d_good, offs)
        heading = h0 + h_slope * delta_offset
    else:
        h_slope, heading = 0.0, float(np.mean(offs))
        h_std = float(np.std(offs))
    per_run = {}
    for run in sorted({f.run for f in figs}):
        z = _zero_crossing([f for f in figs if f.run == run])
        if z is not None:
            per_run[run] = float(z)
    return CalibrationResult(
        delta_offset_deg=float(delta_offset), heading_offset_deg=float(wrap(heading / DEG) * DEG),
        drift_rate_deg_s=drift, steering_gain_deg_s_per_deg=gain, k_bias_s=k_bias,
        rate_residual_std_deg_s=rate_std, delta_offset_std_deg=delta_std, heading_offset_slope=h_slope,
        heading_offset_residual_std_deg=h_std, segments=figs, per_run_delta_offset_deg=per_run,
        warnings=warnings)
