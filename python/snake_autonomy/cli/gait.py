"""`snake_autonomy gait`: run a gait open-loop through the core (CPG -> kinematics, base held
fixed, no physics) and write what it computed: joint angles, body shape, centre of mass, virtual
chassis and bounding box, as plots and a CSV.

    snake_autonomy gait --gait sidewind --duration 10 --out results/gait
"""
import csv
import json
import sys
from pathlib import Path

import numpy as np

from snake_autonomy import _core
from snake_autonomy.paths import config_path, robot_yaml


def add_arguments(parser):
    parser.add_argument("--robot", default="cobra", help="robot name under config/robots/ or a YAML path")
    parser.add_argument("--gaits", default=None, help="gait library YAML (default: config/gaits.yaml)")
    parser.add_argument("--gait", default="sidewind", help="gait name")
    parser.add_argument("--duration", type=float, default=10.0, help="seconds to run")
    parser.add_argument("--dt", type=float, default=0.01, help="step in seconds (0.01: 100 Hz)")
    parser.add_argument("--steer-deg", type=float, default=0.0,
                        help="amplitude-modulation steering delta in degrees (steerable gaits only)")
    parser.add_argument("--out", default="results/gait", help="output folder")


def run_open_loop(model, gaits, gait, duration_s, dt_s, steer_rad=0.0):
    """Steps the CPG from rest and computes the body at every step. Returns a dict of arrays."""
    params = gaits.parameters(gait, model)
    if steer_rad:
        if not gaits.steerable(gait):
            raise ValueError(f"--steer-deg: gait '{gait}' is not steerable")
        params.amplitude = _core.Steering(model).modify_amplitudes(params.amplitude, steer_rad)
    cpg = _core.CPG(model)
    cpg.apply(params)
    kin = _core.Kinematics(model)
    steps = int(round(duration_s / dt_s))
    out = {k: [] for k in ("t", "q", "amplitudes", "com", "vc_yaw", "bbox", "positions")}
    for k in range(steps):
        q = cpg.step(dt_s)
        s = kin.compute([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], q)
        out["t"].append((k + 1) * dt_s)
        out["q"].append(q)
        out["amplitudes"].append(cpg.amplitudes)
        out["com"].append(s.com)
        out["vc_yaw"].append(np.arctan2(s.vc_rotation[1, 0], s.vc_rotation[0, 0]))
        out["bbox"].append(s.bbox_span)
        out["positions"].append(s.link_positions)
    result = {k: np.asarray(v) for k, v in out.items()}
    result["targets"] = params
    result["lags"] = np.diff(cpg.phases)
    return result


def write_plots(result, model, gait, out_dir: Path):
    import matplotlib  # lazy: matplotlib is heavy and only this path needs it

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, q = result["t"], np.degrees(result["q"])
    fig, axes = plt.subplots(2, 2, figsize=(13, 8.5))
    ax = axes[0, 0]
    for i in range(model.num_joints):
        ax.plot(t, q[:, i], lw=1.0, ls="-" if model.axes[i] == "yaw" else "--", label=f"J{i + 1} {model.axes[i]}")
    ax.set(xlabel="time [s]", ylabel="joint angle [deg]", title=f"CPG output, gait '{gait}' (dashed: pitch)")
    ax.legend(ncol=3, fontsize=7)
    ax = axes[0, 1]
    last = result["positions"][-int(len(t) / 10):]  # snapshots over the last tenth of the run
    for k in range(0, len(last), max(1, len(last) // 6)):
        ax.plot(last[k][:, 0], last[k][:, 1], "-o", ms=3, alpha=0.7)
    ax.set(xlabel="x [m] (base frame)", ylabel="y [m]", title="body shape, top view (base fixed)")
    ax.axis("equal")
    ax = axes[1, 0]
    ax.plot(t, result["bbox"][:, 0], label="span x")
    ax.plot(t, result["bbox"][:, 1], label="span y")
    ax.plot(t, result["bbox"][:, 2], label="span z")
    ax.set(xlabel="time [s]", ylabel="bounding box span [m]", title="bounding box (eq. 3.20, 0.1 m padding)")
    ax.legend()
    ax = axes[1, 1]
    ax.plot(t, result["com"][:, 0], label="CoM x")
    ax.plot(t, result["com"][:, 1], label="CoM y")
    ax.plot(t, result["com"][:, 2], label="CoM z")
    ax2 = ax.twinx()
    ax2.plot(t, np.degrees(result["vc_yaw"]), "k:", label="chassis yaw")
    ax2.set_ylabel("virtual chassis yaw [deg]")
    ax.set(xlabel="time [s]", ylabel="centre of mass [m] (base frame)", title="centre of mass and virtual chassis")
    ax.legend(loc="upper left")
    fig.suptitle(f"{model.name}: open-loop '{gait}' through the core (no physics)")
    fig.tight_layout()
    path = out_dir / f"gait_{gait}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(args) -> int:
    try:
        model = _core.RobotModel.from_yaml(str(robot_yaml(args.robot)))
        gaits = _core.GaitLibrary.from_yaml(args.gaits or str(config_path("gaits.yaml")))
    except ValueError as err:
        print(err, file=sys.stderr)
        return 1
    if args.gait not in gaits:
        print(f"--gait: unknown gait '{args.gait}' (known: {', '.join(gaits.names)})", file=sys.stderr)
        return 1
    for name, hi in (("duration", 3600.0), ("dt", 1.0)):
        value = getattr(args, name)
        if not (np.isfinite(value) and value > 0):
            print(f"--{name}: must be a positive number, got {value}", file=sys.stderr)
            return 1
        if value > hi:
            print(f"--{name}: must be at most {hi:g} s, got {value}", file=sys.stderr)
            return 1
    if args.duration / args.dt > 1e6:
        print(f"--duration / --dt: at most 1e6 steps, got {args.duration / args.dt:.3g}", file=sys.stderr)
        return 1
    if not (np.isfinite(args.steer_deg) and abs(args.steer_deg) <= 90.0):
        print(f"--steer-deg: must be within +-90, got {args.steer_deg}", file=sys.stderr)
        return 1
    out_dir = Path(args.out)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f"--out: cannot create the folder {out_dir}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    try:
        result = run_open_loop(model, gaits, args.gait, args.duration, args.dt, np.radians(args.steer_deg))
    except ValueError as err:
        print(err, file=sys.stderr)
        return 1
    with open(out_dir / f"gait_{args.gait}.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s"] + [f"q{i + 1}_rad" for i in range(model.num_joints)]
                   + ["com_x_m", "com_y_m", "com_z_m", "vc_yaw_rad", "bbox_x_m", "bbox_y_m", "bbox_z_m"])
        for k in range(len(result["t"])):
            w.writerow([f"{result['t'][k]:.3f}"] + [f"{v:.6f}" for v in result["q"][k]]
                       + [f"{v:.6f}" for v in result["com"][k]] + [f"{result['vc_yaw'][k]:.6f}"]
                       + [f"{v:.6f}" for v in result["bbox"][k]])
    plot = write_plots(result, model, args.gait, out_dir)
    targets = result["targets"]
    q = result["q"]
    summary = {
        "robot": model.name, "gait": args.gait, "duration_s": args.duration, "dt_s": args.dt,
        "final_amplitudes_deg": np.round(np.degrees(result["amplitudes"][-1]), 3).tolist(),
        "target_amplitudes_deg": np.round(np.degrees(targets.amplitude), 3).tolist(),
        "final_lags_deg": np.round(np.degrees(result["lags"]), 3).tolist(),
        "target_lags_deg": np.round(np.degrees(np.angle(np.exp(1j * np.diff(targets.phase)))), 3).tolist(),
        "max_abs_joint_deg": float(np.degrees(np.abs(q).max())),
        "joint_limit_violations": int(((q < model.joint_lower_rad - 1e-12)
                                       | (q > model.joint_upper_rad + 1e-12)).sum()),
        "bbox_span_mean_m": np.round(result["bbox"].mean(axis=0), 4).tolist(),
    }
    (out_dir / f"gait_{args.gait}.json").write_text(json.dumps(summary, indent=2))
    print(f"{model.name}: gait '{args.gait}' open-loop for {args.duration:g} s at {1 / args.dt:g} Hz")
    print(f"  amplitudes reached [deg]: {summary['final_amplitudes_deg']}")
    print(f"  lags reached       [deg]: {summary['final_lags_deg']}")
    print(f"  lags commanded     [deg]: {summary['target_lags_deg']}")
    print(f"  max |q| {summary['max_abs_joint_deg']:.1f} deg, "
          f"joint-limit violations: {summary['joint_limit_violations']}")
    print(f"  mean bounding box span [m]: {summary['bbox_span_mean_m']}")
    print(f"  wrote {plot}, {out_dir / f'gait_{args.gait}.csv'}, {out_dir / f'gait_{args.gait}.json'}")
    return 0
