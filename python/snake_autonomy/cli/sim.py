"""`snake_autonomy sim`: missions on the simulated robot, without ROS (batch, faster than real time).

    snake_autonomy sim run --mission star --seed 3 --feedback vio --out results/sim/star_s3
    snake_autonomy sim run --mission single_waypoint --start 2.5,1.0,135 --time-limit 120 --out DIR
    snake_autonomy sim experiment star --seeds 0-4 --feedback both --out results/sim/star [--jobs 2]

`run` writes DIR/metrics.json (per waypoint: reached, time_s, final_distance_m, final_yaw_error_deg;
rolled_over, limit_violations, sim_time_s, ...), the CSVs and figures of experiments.write_results,
and with --feedback vio the evaluation of the simulated RTAB-Map in DIR/evaluation. Exit 0 when every
waypoint was reached without roll-over or limit violation, 1 otherwise and on bad input (a mission,
config or option refused: one message), 2 on a command-line usage error.
`experiment` runs one of the thesis's experiments (single, star, bidirectional, disturbance) over
seeds and writes a summary table and figure per feedback; exit 0 when it meets the acceptance.
"""
import math
import sys
from pathlib import Path

from snake_autonomy.missions import MissionError
from snake_autonomy.missions.mission import MAX_COORDINATE_M, MAX_HEADING_DEG, MAX_TIME_LIMIT_S
from snake_autonomy.paths import config_path
from snake_autonomy.runs.batch import BatchRun, RunSpec
from snake_autonomy.runs.mission_experiment import (TABLE_HEADER, TABLE_RULE, parse_seeds, run_experiment,
                                                    run_success, table_row)

EXPERIMENT_NAMES = ("single", "star", "bidirectional", "disturbance")


def _start(text):
    try:
        x, y, h = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--start: expected x,y,heading_deg (e.g. 2.5,1.0,135), got {text!r}") from None
    if not all(math.isfinite(v) for v in (x, y, h)) or max(abs(x), abs(y)) > MAX_COORDINATE_M \
            or abs(h) > MAX_HEADING_DEG:
        raise ValueError(f"--start: x and y within +-{MAX_COORDINATE_M:g} m and a heading within "
                         f"+-{MAX_HEADING_DEG:g} deg, got {text!r}")
    return x, y, h


def _check_options(args) -> None:
    """Range checks of the numeric options (ValueError naming the option and its value)."""
    limit = getattr(args, "time_limit", None)
    if limit is not None and not (math.isfinite(limit) and 0 < limit <= MAX_TIME_LIMIT_S):
        raise ValueError(f"--time-limit: must be a number of seconds in (0, {MAX_TIME_LIMIT_S:g}], got {limit!r}")
    if getattr(args, "seed", 0) < 0:
        raise ValueError(f"--seed: must be >= 0, got {args.seed}")
    if getattr(args, "jobs", 1) < 1:
        raise ValueError(f"--jobs: must be >= 1, got {args.jobs}")


def add_arguments(parser):
    sub = parser.add_subparsers(dest="sim_command", metavar="SIM_COMMAND")
    run = sub.add_parser("run", help="one mission on the simulated robot")
    run.add_argument("--mission", required=True, help="mission file or provided mission name (config/missions)")
    run.add_argument("--seed", type=int, default=0, help="randomised physics and sensor noise")
    run.add_argument("--feedback", choices=("mocap", "vio", "vo"), default="mocap",
                     help="base pose from motion capture, the simulated RTAB-Map (a noise model), or the "
                          "visual-inertial odometry on the rendered head camera and the IMU (in the odometry room)")
    run.add_argument("--out", required=True, metavar="DIR", help="results folder")
    run.add_argument("--start", default="0,0,0", metavar="X,Y,HEADING_DEG",
                     help="centre of mass of a straight body and its heading (direction of travel)")
    run.add_argument("--time-limit", type=float, metavar="S", help="override the mission's time limit")
    _common(run)
    exp = sub.add_parser("experiment", help="one of the thesis's experiments over seeds (chapter 4.2)")
    exp.add_argument("name", choices=EXPERIMENT_NAMES, help="the experiment")
    exp.add_argument("--seeds", default="0-4", help="e.g. 0-4 or 0,3")
    exp.add_argument("--feedback", choices=("mocap", "vio", "vo", "both"), default="both",
                     help="the base pose: motion capture, the simulated RTAB-Map, the visual-inertial odometry, "
                          "or both (motion capture and the simulated RTAB-Map, each in turn)")
    exp.add_argument("--out", required=True, metavar="DIR", help="results folder")
    exp.add_argument("--jobs", type=int, default=1, help="parallel runs (the machine is shared)")
    exp.add_argument("--starts", help="single only: a subset of the 13 start poses, e.g. 0,7 or 0-3 (default all)")
    exp.add_argument("--time-limit", type=float, metavar="S", help="override the mission's time limit")
    _common(exp)


def _common(p):
    root = config_path()
    p.add_argument("--sim-config", default=str(root / "sim.yaml"), help="simulated robot")
    p.add_argument("--gaits", default=str(root / "gaits.yaml"), help="gait library")
    p.add_argument("--no-plots", action="store_true", help="metrics and CSVs only")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args) -> int:
    if args.sim_command is None:
        print("snake_autonomy sim: give a command: run or experiment (--help)", file=sys.stderr)
        return 2
    try:
        _check_options(args)
        if args.sim_command == "run":
            return _run(args)
        return _experiment(args)
    except (ValueError, MissionError, OSError) as exc:
        print(f"snake_autonomy sim {args.sim_command}: {exc}", file=sys.stderr)
        return 1


def _run(args) -> int:
    spec = RunSpec(mission=args.mission, seed=args.seed, feedback=args.feedback, start=_start(args.start),
                   time_limit_s=args.time_limit, sim_config=args.sim_config, gaits=args.gaits)
    run = BatchRun(spec)
    result = run.run(progress=not args.no_progress and sys.stderr.isatty())
    m = result.write(args.out, plots=not args.no_plots)
    print(f"{run.mission.name}, seed {spec.seed}, {spec.feedback}: {m['outcome']}; "
          f"{m['waypoints_reached']}/{m['num_waypoints']} waypoints in {m['mission_time_s']:.1f} s simulated "
          f"({m['real_time_factor']:.0f}x real time); rolled over: {m['rolled_over']}; "
          f"limit violations: {m['limit_violations']}")
    for w in m["waypoints"]:
        t = "-" if w["time_s"] is None else f"{w['time_s']:.0f} s"
        fd = "-" if w["final_distance_m"] is None else f"{w['final_distance_m']:.2f} m"
        fy = "-" if w["final_yaw_error_deg"] is None else f"{w['final_yaw_error_deg']:+.1f} deg"
        print(f"  WP{w['index']}: reached {w['reached']}, {t}, final distance {fd}, yaw error {fy}")
    for d in m["disturbances"]:
        print(f"  {d['description']} at {d['t_s']:.1f} s: recovered {d['recovered']}")
    print(f"results in {args.out}")
    return 0 if run_success(m) else 1


def _experiment(args) -> int:
    seeds = parse_seeds(args.seeds)
    feedbacks = ("mocap", "vio") if args.feedback == "both" else (args.feedback,)
    summaries = []
    for fb in feedbacks:
        summaries.append(run_experiment(args.name, seeds, fb, args.out, jobs=max(1, args.jobs),
                                        plots=not args.no_plots, progress=not args.no_progress,
                                        starts=parse_seeds(args.starts) if args.starts else None,
                                        time_limit_s=args.time_limit, sim_config=args.sim_config,
                                        gaits=args.gaits))
    print(TABLE_HEADER)
    print(TABLE_RULE)
    for s in summaries:
        print(table_row(s))
    for s in summaries:
        print(f"{s['experiment']} {s['feedback']}: {'accepted' if s['accepted'] else 'NOT accepted'}; "
              f"{s['simulated_s']:.0f} s simulated in {s['wall_s']:.0f} s; summary in "
              f"{Path(args.out) / s['feedback']}")
    return 0 if all(s["accepted"] for s in summaries) else 1
