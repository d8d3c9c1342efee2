"""`snake_autonomy gait-map --robot R --gait G --out DIR`: a gait map (runs/gait_map.py) swept on
Dask (runs/sweep_runner.py): DIR/points.csv, DIR/gait_map.yaml (fits; `follower:` keys that
config/nav.yaml's `follower.gait_map: FILE` reads) and DIR/gait_map.png.

    snake_autonomy gait-map --robot cobra --gait rectilinear --amplitudes 0.01 0.02 \\
        --kappas -1 -0.5 0 0.5 1 --out results/gait_map/cobra_rect
    snake_autonomy gait-map --robot chang_rectilinear --driver-gait rectilinear_chang --amplitudes 0.02 \
        --wavelength 0.5 --kappas -1.5 -1 -0.5 0 0.5 1 1.5 --flat-belly 0.8 --out DIR   # through the driver
    snake_autonomy gait-map --robot cobra --gait sidewinding --amplitudes 35 45 --deltas -10 0 10 --out DIR
    ... --engine serial|threads|dask [--scheduler tcp://HOST:8786] [--workers 2]
"""
import csv
import sys
import time
from pathlib import Path

import yaml

from snake_autonomy.runs.gait_map import fit_gait_map, gait_map_points, plot_gait_map, simulate_point
from snake_autonomy.runs.sweep_runner import open_executor, run_tasks


def add_engine_arguments(p) -> None:
    p.add_argument("--engine", choices=("dask", "threads", "serial"), default="dask",
                   help="dask: a LocalCluster (or --scheduler); threads/serial: reference engines")
    p.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (tcp://host:8786)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster processes / threads")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (on stderr)")


def add_arguments(p) -> None:
    p.add_argument("--robot", default="cobra", help="config/robots/NAME.yaml or a YAML file")
    p.add_argument("--gait", choices=("rectilinear", "sidewinding"), default="rectilinear", help="the gait swept")
    p.add_argument("--amplitudes", nargs="+", type=float, default=None,
                   help="rectilinear: A in m (default 0.01 0.02); sidewinding: yaw amplitude deg (35 45)")
    p.add_argument("--kappas", nargs="+", type=float, default=[-1.0, -0.5, 0.0, 0.5, 1.0],
                   help="rectilinear: body curvatures 1/m")
    p.add_argument("--deltas", nargs="+", type=float, default=[-10.0, 0.0, 10.0],
                   help="sidewinding: steering delta deg")
    p.add_argument("--driver-gait", default="", metavar="NAME",
                   help="rectilinear: run this config/gaits.yaml entry (steering: curvature) through the C++ "
                        "driver instead of the Python reference; --amplitudes and --wavelength then only "
                        "label it (give the A and lambda it was derived for, one amplitude)")
    p.add_argument("--wavelength", type=float, default=1.0, metavar="M", help="rectilinear: lambda in m")
    p.add_argument("--nominal-amplitude", type=float, default=None,
                   help="the amplitude whose fit becomes the follower's keys (default: the fastest)")
    p.add_argument("--measure-cycles", type=int, default=4, help="gait cycles measured per point")
    p.add_argument("--seed", type=int, default=0, help="plant seed")
    p.add_argument("--scales", action="store_true", help="ventral scales on (config/sim.yaml scales:)")
    p.add_argument("--flat-belly", type=float, default=0.0, metavar="F",
                   help="plant option physics.flat_belly_fraction (nav runs: config/nav.yaml plant:)")
    p.add_argument("--out", required=True, metavar="DIR", help="points.csv, gait_map.yaml, gait_map.png")
    add_engine_arguments(p)


def write_csv(rows, path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def main(args) -> int:
    amps = args.amplitudes or ([0.01, 0.02] if args.gait == "rectilinear" else [35.0, 45.0])
    if args.driver_gait and len(amps) != 1:
        print(f"gait-map: --driver-gait runs one gait: give the one amplitude it was derived for, got {amps}",
              file=sys.stderr)
        return 1
    try:
        points = gait_map_points(args.robot, args.gait, amps, args.kappas, args.deltas, seed=args.seed,
                                 scales=args.scales, flat_belly_fraction=args.flat_belly,
                                 measure_cycles=args.measure_cycles, wavelength_m=args.wavelength,
                                 driver_gait=args.driver_gait)
    except ValueError as e:
        print(f"gait-map: {e}", file=sys.stderr)
        return 1
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with open_executor(args.engine, args.scheduler, args.workers) as ex:
        rows = run_tasks(ex, simulate_point, points, desc=f"gait map {args.robot} {args.gait}",
                         progress=not args.no_progress)
    wall = time.perf_counter() - t0
    summary = fit_gait_map(rows, args.nominal_amplitude)
    doc = {"robot": args.robot, "gait": args.gait, "driver_gait": args.driver_gait or None,
           "wavelength_m": args.wavelength if args.gait == "rectilinear" else None, "scales": bool(args.scales),
           "flat_belly_fraction": args.flat_belly, "seed": args.seed,
           "engine": args.engine, "points": len(rows), "wall_s": round(wall, 1), **summary}
    (out / "gait_map.yaml").write_text(
        "# snake_autonomy gait-map: steady body velocity fits (runs/gait_map.py). follower: keys are\n"
        "# what config/nav.yaml's `follower.gait_map: FILE` reads.\n" + yaml.safe_dump(doc, sort_keys=False))
    write_csv(rows, out / "points.csv")
    plot_gait_map(rows, summary, out / "gait_map.png")
    print(f"{len(rows)} points in {wall:.0f} s on {args.engine}: {out / 'gait_map.yaml'}")
    for f in summary["fits"]:
        if f.get("rolled_over"):
            print(f"  amplitude {f['amplitude']:g}: every point rolled over")
            continue
        fit = (f"omega = {f['omega_per_steer']:.4f} x steer {f['omega_offset_rad_s']:+.4f} rad/s (r2 "
               f"{f['r2']:.2f})" if "omega_per_steer" in f else "no fit (one steering value)")
        print(f"  amplitude {f['amplitude']:g}: forward {1000 * f['speed_m_s']:.1f} mm/s "
              f"({1000 * f['speed_min_m_s']:.1f}..{1000 * f['speed_max_m_s']:.1f}), {fit}; "
              f"{f['points']} upright points")
    if any(r["rolled_over"] for r in rows):
        print(f"  {sum(r['rolled_over'] for r in rows)} point(s) rolled over (excluded from fits)",
              file=sys.stderr)
    return 0
