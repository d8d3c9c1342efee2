"""Gait maps (Chang et al. fig. 2): sweeps of the plant over the gait's amplitude A and
the body curvature kappa (COBRA's sidewinding: amplitude and the steering delta) giving the steady
body velocity xi = (xi_x, xi_y, xi_w); a linear fit omega(kappa) (its inverse is the follower's
kappa(omega)) and the forward speed, written to YAML that config/nav.yaml's follower reads
(`follower.gait_map: FILE`) and plotted.

    points = gait_map_points("cobra", "rectilinear", amplitudes=[0.01, 0.02], kappas=[-1, 0, 1])
    with open_executor("dask") as ex:
        rows = run_tasks(ex, simulate_point, points)
    summary = fit_gait_map(rows, nominal_amplitude=0.02)

A rectilinear point runs the Python reference (planning/rectilinear/gait.py) with its A, lambda and
f, or, with driver_gait, that config/gaits.yaml entry (steering: curvature) through the C++ driver
(runs/gait_driver.py: the gait nav runs drive; its wave is the entry's, amplitude and wavelength are
then the values it was derived for, recorded as labels; its CPG ramps the wave in from the hold
posture during ramp_s).

One point: the gait ramped in over ramp_s, settle_s more to reach the steady state, then measure_s
(whole gait cycles) sampled once per cycle at the same phase (stroboscopic: the gait's own
oscillation cancels). xi is the centroid's displacement of the kinematic frames in the body frame of
the window's start (x: base_link's heading there, y: left) per second, and xi_w base_link's
unwrapped yaw change per second. Every point is a pure function of its fields (seed included): the
same points give the same numbers on any engine.
"""
import dataclasses
import math
from dataclasses import asdict, dataclass
from typing import Dict, List, Optional, Sequence

import numpy as np

from snake_autonomy import _core
from snake_autonomy.paths import config_path, robot_yaml
from snake_autonomy.planning.rectilinear.gait import RectilinearGait
from snake_autonomy.runs.gait_driver import PlantGaitDriver
from snake_autonomy.safe_yaml import load_yaml_file
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.scales import ScaledPlant
from snake_autonomy.sim.serpenoid import SIDEWINDING

GAITS = ("rectilinear", "sidewinding")


@dataclass(frozen=True)
class GaitPoint:
    robot: str                   # config/robots/NAME.yaml or a YAML path
    gait: str                    # rectilinear | sidewinding
    amplitude: float             # rectilinear: A (m); sidewinding: yaw amplitude (deg)
    kappa_per_m: float = 0.0     # rectilinear steering
    delta_deg: float = 0.0       # sidewinding steering
    seed: int = 0                # plant parameters drawn with this seed (config/sim.yaml)
    randomize: bool = False      # False: the plant's nominal parameters
    scales: bool = False
    flat_belly_fraction: float = 0.0   # the plant option (nav runs use nav.yaml plant:)
    wavelength_m: float = 1.0
    frequency_hz: float = 0.4
    ramp_s: float = 2.0
    settle_cycles: int = 1
    measure_cycles: int = 4
    driver_gait: str = ""        # a gaits.yaml entry driven through the C++ driver (empty: the reference)


def gait_map_points(robot: str, gait: str, amplitudes: Sequence[float], kappas: Sequence[float] = (0.0,),
                    deltas: Sequence[float] = (0.0,), **kw) -> List[GaitPoint]:
    if gait not in GAITS:
        raise ValueError(f"gait: expected one of {', '.join(GAITS)}, got {gait!r}")
    if kw.get("driver_gait"):
        if gait != "rectilinear":
            raise ValueError(f"driver_gait {kw['driver_gait']!r}: only with gait rectilinear (curvature steering)")
        kw = {**kw, "frequency_hz": driver_gait_frequency_hz(kw["driver_gait"])}
    if gait == "rectilinear":
        return [GaitPoint(robot, gait, float(a), kappa_per_m=float(k), **kw) for a in amplitudes for k in kappas]
    return [GaitPoint(robot, gait, float(a), delta_deg=float(d), **kw) for a in amplitudes for d in deltas]


def driver_gait_frequency_hz(name: str, gaits_yaml=None) -> float:
    """The frequency of a config/gaits.yaml entry with steering: curvature (ValueError naming it else)."""
    path = gaits_yaml or config_path("gaits.yaml")
    entry = ((load_yaml_file(path) or {}).get("gaits") or {}).get(name)
    if not isinstance(entry, dict) or entry.get("steering") != "curvature":
        raise ValueError(f"driver_gait: {name!r} is not a gait of {path} with steering: curvature")
    f = entry.get("frequency_hz")
    if not isinstance(f, (int, float)) or not f > 0:
        raise ValueError(f"driver_gait: {name!r}: frequency_hz must be > 0, got {f!r}")
    return float(f)


def _joint_pattern(point: GaitPoint, robot):
    if point.gait == "rectilinear":
        g = RectilinearGait(point.amplitude, point.wavelength_m, point.frequency_hz)
        return (lambda t: g.joint_angles(robot, t, point.kappa_per_m)), point.frequency_hz
    g = SIDEWINDING.__class__(**{**asdict(SIDEWINDING), "yaw_amplitude_rad": math.radians(point.amplitude),
                                 "delta_rad": math.radians(point.delta_deg)})
    return (lambda t: g.joint_angles(robot, t)), g.frequency_hz


def simulate_point(point: GaitPoint) -> Dict:
    """The steady body velocity of one gait-map point (runs the plant; a module-level function so
    that process-based engines can import it)."""
    robot = _core.RobotModel.from_yaml(str(robot_yaml(point.robot)))
    cfg = SimConfig.from_yaml(str(config_path("sim.yaml")))
    cfg = dataclasses.replace(cfg.with_flat_belly(point.flat_belly_fraction),
                              scales=dataclasses.replace(cfg.scales, enabled=point.scales))
    params = cfg.draw(seed=point.seed, num_joints=robot.num_joints, randomize=point.randomize)
    plant = ScaledPlant(robot, params, (0.0, 0.0, 0.0))
    dt = 0.01
    if point.driver_gait:
        drive = PlantGaitDriver(robot, plant)
        drive.command(point.driver_gait, kappa_per_m=point.kappa_per_m)
        f = point.frequency_hz

        def advance(t):
            drive.step(t, dt)
    else:
        pattern, f = _joint_pattern(point, robot)

        def advance(t):
            ramp = min(1.0, t / point.ramp_s) if point.ramp_s > 0 else 1.0
            plant.set_joint_targets(pattern(0.0) * ramp if t < point.ramp_s else pattern(t - point.ramp_s))
    period = 1.0 / f
    t, max_tilt = 0.0, 0.0
    while t < point.ramp_s - 1e-9:
        advance(t)
        t += dt
        plant.step_to(t)
    samples = []
    total = point.settle_cycles + point.measure_cycles
    for cycle in range(total + 1):
        t_end = point.ramp_s + cycle * period
        while t < t_end - 1e-9:
            advance(t)
            t += dt
            plant.step_to(t)
            max_tilt = max(max_tilt, plant.base_tilt_deg())
        if cycle >= point.settle_cycles:
            samples.append(stroboscopic_sample(plant))
    xi_x, xi_y, xi_w = body_velocity(samples, point.measure_cycles * period)
    return {**asdict(point), "xi_x_m_s": float(xi_x), "xi_y_m_s": float(xi_y), "xi_w_rad_s": float(xi_w),
            "max_tilt_deg": float(max_tilt), "rolled_over": bool(max_tilt > 60.0)}


def stroboscopic_sample(plant):
    """(centroid of the kinematic frames' xy, base_link's yaw): one sample of body_velocity."""
    T = plant.frame_transform("base_link")
    return plant.frame_positions().mean(axis=0)[:2], math.atan2(T[1, 0], T[0, 0])


def body_velocity(samples, duration_s: float):
    """xi = (xi_x, xi_y, xi_w) from stroboscopic samples (one per gait cycle, same phase) spanning
    duration_s: the centroid's displacement in the body frame of the first sample (x: base_link's
    heading, y: left) per second, and base_link's unwrapped yaw change per second."""
    yaws = np.unwrap([s[1] for s in samples])
    th = yaws[0]
    d = np.asarray(samples[-1][0]) - np.asarray(samples[0][0])
    return ((math.cos(th) * d[0] + math.sin(th) * d[1]) / duration_s,
            (-math.sin(th) * d[0] + math.cos(th) * d[1]) / duration_s,
            (yaws[-1] - yaws[0]) / duration_s)


def fit_gait_map(rows: List[Dict], nominal_amplitude: Optional[float] = None) -> Dict:
    """Per amplitude: omega = omega_per_kappa * kappa + omega_offset (least squares over the points
    that did not roll over), its r^2, the forward speed (mean xi_x over those points, and at kappa
    0). The follower's keys come from the nominal amplitude (default: the fastest straight one)."""
    fits = []
    for a in sorted({r["amplitude"] for r in rows}):
        pts = [r for r in rows if r["amplitude"] == a and not r["rolled_over"]]
        if not pts:
            fits.append({"amplitude": a, "points": 0, "rolled_over": True})
            continue
        steer = np.array([r["kappa_per_m"] if r["gait"] == "rectilinear" else r["delta_deg"] for r in pts])
        w = np.array([r["xi_w_rad_s"] for r in pts])
        vx = np.array([r["xi_x_m_s"] for r in pts])
        fit = {"amplitude": a, "points": len(pts), "rolled_over": False,
               "speed_m_s": float(np.mean(vx)), "speed_min_m_s": float(np.min(vx)),
               "speed_max_m_s": float(np.max(vx)), "steer_min": float(steer.min()),
               "steer_max": float(steer.max())}
        straight = [r["xi_x_m_s"] for r, s in zip(pts, steer) if s == 0.0]
        if straight:
            fit["speed_straight_m_s"] = float(straight[0])
        if len(set(steer.tolist())) > 1:
            slope, offset = np.polyfit(steer, w, 1)
            resid = w - (slope * steer + offset)
            ss = float(np.sum((w - w.mean()) ** 2))
            fit.update(omega_per_steer=float(slope), omega_offset_rad_s=float(offset),
                       r2=float(1.0 - np.sum(resid ** 2) / ss) if ss > 0 else 1.0)
        fits.append(fit)
    usable = [f for f in fits if "omega_per_steer" in f and f["speed_m_s"] > 0]
    out = {"fits": fits}
    if usable:
        if nominal_amplitude is not None and any(f["amplitude"] == nominal_amplitude for f in usable):
            nominal = next(f for f in usable if f["amplitude"] == nominal_amplitude)
        else:
            nominal = max(usable, key=lambda f: f.get("speed_straight_m_s", f["speed_m_s"]))
        out["nominal_amplitude"] = nominal["amplitude"]
        if rows and rows[0]["gait"] == "rectilinear":
            out["follower"] = {"speed_m_s": nominal["speed_m_s"],
                               "omega_per_kappa": nominal["omega_per_steer"],
                               "omega_offset_rad_s": nominal["omega_offset_rad_s"],
                               "kappa_max_per_m": max(abs(nominal["steer_min"]), abs(nominal["steer_max"]))}
    return out


def plot_gait_map(rows: List[Dict], summary: Dict, path) -> None:
    import matplotlib  # lazy: matplotlib is heavy and only this path needs it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rect = rows[0]["gait"] == "rectilinear"
    key, label = ("kappa_per_m", "body curvature kappa (1/m)") if rect else ("delta_deg", "steering delta (deg)")
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for a in sorted({r["amplitude"] for r in rows}):
        pts = sorted((r for r in rows if r["amplitude"] == a), key=lambda r: r[key])
        s = [r[key] for r in pts]
        name = f"A {a * 100:.1f} cm" if rect else f"amp {a:.0f} deg"
        axes[0].plot(s, [1000 * r["xi_x_m_s"] for r in pts], "o-", label=name)
        axes[1].plot(s, [1000 * r["xi_y_m_s"] for r in pts], "o-", label=name)
        axes[2].plot(s, [math.degrees(r["xi_w_rad_s"]) for r in pts], "o-", label=name)
        for ax, k in zip(axes, ("xi_x_m_s", "xi_y_m_s", "xi_w_rad_s")):
            for r in pts:
                if r["rolled_over"]:
                    ax.plot(r[key], 1000 * r[k] if k != "xi_w_rad_s" else math.degrees(r[k]), "rx", ms=9)
    for f in summary["fits"]:
        if "omega_per_steer" in f:
            s = np.linspace(f["steer_min"], f["steer_max"], 2)
            axes[2].plot(s, np.degrees(f["omega_per_steer"] * s + f["omega_offset_rad_s"]), "k--", lw=0.8)
    for ax, t in zip(axes, ("xi_x forward (mm/s)", "xi_y left (mm/s)", "xi_w turn rate (deg/s)")):
        ax.set_xlabel(label)
        ax.set_title(t)
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize=8)
    fig.suptitle(f"gait map: {rows[0]['robot']} {rows[0]['gait']} (x: rolled over)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
