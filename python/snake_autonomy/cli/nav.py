"""`snake_autonomy nav ...`: navigation among obstacles (Chang et al.).

    snake_autonomy nav check-world FILE...          validate world files (every problem listed)
    snake_autonomy nav train-classifier --out FILE  render a labelled training set, train the
                                                    monocular block classifier, write FILE (joblib)
                                                    and FILE.json (held-out figures, both methods)
    snake_autonomy nav eval-perception [--model FILE] [--scenes N] [--no-progress]
                                                    precision/recall and ms per frame of the depth
                                                    method (and the classifier) on held-out scenes
    snake_autonomy nav run --world FILE [--robot R] [--perception depth|mono|truth] [--seed N]
                           [--pose-source mocap|vio|vo|truth] [--depth-model noisy|perfect]
                           [--time-limit S] [--classifier FILE] [--no-progress] --out DIR
                                                    the closed loop in batch (runs/nav_batch.py):
                                                    DIR/metrics.json, topview.png, frames/
    snake_autonomy nav experiment --worlds N --seeds 0-4 [--perception depth|mono|both|truth]
                           [--family corridors|barn | --world-files GLOB] [--first-world K]
                           [--robot R] [--time-limit S|auto] [--time-factor F]
                           [--pose-source mocap|vio|vo|truth] [--depth-model noisy|perfect]
                           [--engine dask|threads|serial] [--scheduler ADDR] --out DIR
                                                    generated worlds K..K+N-1 of a family
                                                    (sim/nav_worlds.py), or the user's own world
                                                    files; auto: 3 x each world's straight-line time
                                                    on Dask: DIR/runs.csv, summary.json, table.md
    snake_autonomy nav worlds [--family barn|corridors] [--first-world K] [--worlds N] [--robot R] --out DIR
                                                    the generated worlds as world files and top
                                                    views: DIR/NAME.yaml, DIR/NAME.png
"""
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import yaml

from snake_autonomy import _core
from snake_autonomy.cli.gait_map import add_engine_arguments, write_csv
from snake_autonomy.paths import config_path, robot_yaml
from snake_autonomy.perception.block_classifier import BlockClassifier
from snake_autonomy.perception.depth_traversability import DepthTraversability
from snake_autonomy.perception.ground_region import precision_recall, traversable
from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera, nav_config_path
from snake_autonomy.runs.nav_batch import DEPTH_MODELS, POSE_SOURCES, NavRun, NavRunSpec
from snake_autonomy.runs.nav_experiment import (TIME_FACTOR, estimation_table, experiment_tasks, markdown_table,
                                                outcome_table, run_nav_task, summarise, time_limit_s)
from snake_autonomy.runs.nav_ros_experiment import check_robot, comparison_table, run_experiment
from snake_autonomy.runs.nav_world_set import generated_worlds, world_files
from snake_autonomy.runs.render_set import render_scenes
from snake_autonomy.runs.sweep_runner import open_executor, progress_bar, run_tasks
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.world_file import WorldError, load_world


def add_arguments(parser):
    sub = parser.add_subparsers(dest="nav_command", metavar="ACTION")
    chk = sub.add_parser("check-world", help="validate world files; list every problem")
    chk.add_argument("files", nargs="+", metavar="FILE", help="world files (YAML)")
    tr = sub.add_parser("train-classifier", help="render a training set and train the block classifier")
    tr.add_argument("--out", required=True, metavar="FILE", help="model file to write (joblib)")
    tr.add_argument("--scenes", type=int, default=60, help="training scenes (one frame each)")
    tr.add_argument("--test-scenes", type=int, default=15, help="held-out scenes for the figures")
    tr.add_argument("--seed", type=int, default=0, help="training scenes' seed; held-out: seed + 100000")
    tr.add_argument("--no-progress", action="store_true", help="no progress bar (rendered scenes, on stderr)")
    ev = sub.add_parser("eval-perception", help="depth (and classifier) traversability on held-out scenes")
    ev.add_argument("--model", metavar="FILE", help="a classifier model from train-classifier")
    ev.add_argument("--scenes", type=int, default=15, help="held-out scenes (one frame each)")
    ev.add_argument("--seed", type=int, default=100000,
                    help="the scenes' seed (train-classifier's held out: its seed + 100000)")
    ev.add_argument("--no-progress", action="store_true", help="no progress bar (rendered scenes, on stderr)")
    run = sub.add_parser("run", help="the closed loop on the simulated robot in batch")
    run.add_argument("--world", required=True, metavar="FILE", help="world file (YAML)")
    run.add_argument("--perception", choices=("depth", "mono", "truth"), default="depth",
                     help="truth: the segmentation render through the classifier's cells (a perfect classifier)")
    run.add_argument("--seed", type=int, default=0, help="plant seed (physics and sensor noise)")
    run.add_argument("--time-limit", type=float, default=1200.0, metavar="S", help="simulated seconds (> 0)")
    run.add_argument("--classifier", metavar="FILE", help="model of train-classifier (mono)")
    run.add_argument("--out", required=True, metavar="DIR", help="metrics.json, topview.png, frames/")
    run.add_argument("--flat-belly", type=float, default=None, metavar="F",
                     help="plant option: flat belly F x the link diameter wide (default nav.yaml plant:)")
    run.add_argument("--no-progress", action="store_true", help="no progress bar (simulated seconds, on stderr)")
    ex = sub.add_parser("experiment", help="generated (or your own) worlds x seeds: success rate, collisions, time",
                        description=WORLDS_CONVENTION)
    for p in (run, ex):
        p.add_argument("--pose-source", choices=POSE_SOURCES, default="mocap",
                       help="the planner's base pose: mocap (motion capture with its noise, as sim.launch), "
                            "vio (the simulated RTAB-Map through the tracking gate and pose "
                            "remapper: drift, tracking losses), vo (the visual-inertial odometry vio_node runs, "
                            "on rendered frames and the IMU: only on worlds with floor_texture dots) or truth "
                            "(the plant's, a diagnostic)")
        p.add_argument("--depth-model", choices=DEPTH_MODELS, default=None,
                       help="the head camera's depth: noisy (D435i-like, config/sim.yaml depth_noise:) or "
                            "perfect (a diagnostic); default: depth_noise.enabled")
    ex.add_argument("--worlds", type=int, default=20,
                    help="generated worlds K..K+N-1 of the family (sim/nav_worlds.py; not with --world-files)")
    ex.add_argument("--first-world", type=int, default=0, metavar="K",
                    help="the first generated world: 0-19 tune, 100 up held out (reports)")
    ex.add_argument("--family", choices=("corridors", "barn"), default=None,
                    help="generated worlds: corridors (default: 1-3 cylinders, goal 1.4 m ahead) or barn "
                         "(BARN-like cluttered 5 x 4 m fields, goal >= 3 m away, a path for the robot's footprint)")
    ex.add_argument("--world-files", metavar="GLOB",
                    help="your own world files (sorted; quote the glob) instead of a generated family")
    ex.add_argument("--seeds", default="0-4", help="plant seeds: 0-4 or 0,2,3")
    ex.add_argument("--perception", choices=("depth", "mono", "both", "truth"), default="depth",
                    help="both: depth and mono; truth: the segmentation render through the classifier's cells")
    ex.add_argument("--time-limit", default="auto", metavar="S|auto",
                    help="seconds per run, or auto (default): --time-factor x the straight-line time from "
                         "the start to the goal's disc at the robot's follower speed (its nav config)")
    ex.add_argument("--time-factor", type=float, default=None, metavar="F",
                    help="with --time-limit auto (default 3; runs/nav_experiment.py time_limit_s)")
    ex.add_argument("--classifier", metavar="FILE", help="model of train-classifier (mono, both)")
    ex.add_argument("--keep-runs", action="store_true", help="each run's figures under DIR/runs/")
    ex.add_argument("--out", required=True, metavar="DIR", help="runs.csv, summary.json, table.md, worlds/")
    add_engine_arguments(ex)
    wd = sub.add_parser("worlds", help="write generated worlds as world files with a top view each",
                        description=WORLDS_CONVENTION)
    wd.add_argument("--family", choices=("barn", "corridors"), default="barn", help="generated world family")
    wd.add_argument("--first-world", type=int, default=0, metavar="K", help="0-19 tune, 100 up held out")
    wd.add_argument("--worlds", type=int, default=5, metavar="N", help="generated worlds K..K+N-1")
    wd.add_argument("--out", required=True, metavar="DIR", help="DIR/NAME.yaml (sim.launch world:=FILE), DIR/NAME.png")
    rx = sub.add_parser("ros-experiment", help="worlds x seeds through ROS (sim.launch) in real time, each "
                        "beside its batch run: one table", description=WORLDS_CONVENTION)
    rx.add_argument("--world-files", metavar="GLOB", help="world files (sorted; quote the glob)")
    rx.add_argument("--family", choices=("corridors", "barn"), default=None,
                    help="generated worlds instead (default corridors), written to DIR/worlds/")
    rx.add_argument("--first-world", type=int, default=0, metavar="K", help="0-19 tune, 100 up held out")
    rx.add_argument("--worlds", type=int, default=3, metavar="N", help="generated worlds K..K+N-1")
    rx.add_argument("--seeds", default="0", help="plant seeds: 0-4 or 0,2,3")
    rx.add_argument("--perception", choices=("depth", "mono"), default="depth",
                    help="traversability from depth or the classifier")
    rx.add_argument("--classifier", metavar="FILE", help="model of train-classifier (mono)")
    rx.add_argument("--time-limit", default="auto", metavar="S|auto",
                    help="seconds after the first command that moves, or auto (as nav experiment)")
    rx.add_argument("--time-factor", type=float, default=None, metavar="F", help="with --time-limit auto")
    rx.add_argument("--out", required=True, metavar="DIR", help="table.md, summary.json, runs/, worlds/")
    rx.add_argument("--no-progress", action="store_true", help="no progress bar (ROS + batch runs, on stderr)")
    for p in (tr, ev, run, ex, wd, rx):
        p.add_argument("--robot", default="cobra", help="robot name (config/robots/NAME.yaml) or YAML file")
    for p in (tr, ev, run, ex, rx):        # not `worlds`: a world depends on the robot only
        p.add_argument("--config", default=None,
                       help="nav config (default: config/nav_ROBOT.yaml if it exists, else config/nav.yaml); "
                       "generated worlds do not depend on it")


def _setup(args):
    cfg = NavConfig.from_yaml(args.config or nav_config_path(args.robot))
    robot = _core.RobotModel.from_yaml(str(robot_yaml(args.robot)))
    params = SimConfig.from_yaml(str(config_path("sim.yaml"))).draw(seed=0)
    return cfg, robot, params


def evaluate(cfg, robot, frames, classifier=None) -> dict:
    """Precision/recall (pixels of the grown region vs the segmentation's, grown the same way)
    and ms per frame, per method, over the frames."""
    methods = {}
    dt = DepthTraversability(cfg.intrinsics, T_ground_camera(cfg.mount, robot.link_radius_m + 0.001), cfg.depth)
    methods["depth"] = (lambda f: dt(f.depth_m), (cfg.depth.block_px, cfg.depth.block_px))
    if classifier is not None:
        margin = cfg.classifier.ground_margin
        methods["mono"] = (lambda f: classifier.traversable(f.rgb, margin), (classifier.block_px, classifier.cell_px))
    out = {}
    for name, (fn, (block, stride)) in methods.items():
        ps, rs, ms = [], [], []
        for f in frames:
            t = time.perf_counter()
            pred = fn(f)
            ms.append(1000.0 * (time.perf_counter() - t))
            p, r = precision_recall(pred, traversable(f.ground_truth_ground(), block, stride_px=stride))
            ps.append(p)
            rs.append(r)
        out[name] = {"precision": float(np.mean(ps)), "recall": float(np.mean(rs)),
                     "precision_min": float(np.min(ps)), "recall_min": float(np.min(rs)),
                     "ms_per_frame_median": float(np.median(ms)), "frames": len(frames),
                     "truth_block_px": block, "truth_stride_px": stride}
    return out


def _counted(items, total: int, desc: str, enabled: bool):
    """The items as they come, counted on a progress bar on stderr (none when not enabled)."""
    bar = progress_bar(total, desc, "scene", enabled=enabled)
    try:
        for item in items:
            yield item
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()


def _print(results: dict) -> None:
    for name, r in results.items():
        print(f"  {name:5s}: precision {r['precision']:.3f} (min {r['precision_min']:.3f}), recall "
              f"{r['recall']:.3f} (min {r['recall_min']:.3f}), {r['ms_per_frame_median']:.1f} ms/frame "
              f"median, {r['frames']} held-out frames")


def main(args) -> int:
    if args.nav_command == "check-world":
        bad = 0
        for f in args.files:
            try:
                w = load_world(f)
                print(f"{f}: ok: start {list(w.start)}, goal {list(w.goal)} r {w.goal_radius_m} m, "
                      f"{len(w.obstacles)} obstacle(s), floor {w.floor_texture}")
            except WorldError as e:
                print(str(e), file=sys.stderr)
                bad += 1
        return 1 if bad else 0
    if args.nav_command == "train-classifier":
        cfg, robot, params = _setup(args)
        t0 = time.perf_counter()
        scenes = render_scenes(robot, params, args.scenes, args.seed, cfg.intrinsics, cfg.mount, depth=False)
        train = [(f.rgb, f.ground_truth_ground()) for f in _counted(
            scenes, args.scenes, "nav train-classifier: rendering", not args.no_progress)]
        t1 = time.perf_counter()
        clf = BlockClassifier.train(train, cfg.classifier.block_px, cfg.classifier.dct_coefficients,
                                    cfg.classifier.svm_c, stride_px=cfg.classifier.stride_px,
                                    ground_fraction=cfg.classifier.ground_fraction)
        t2 = time.perf_counter()
        clf.save(args.out)
        test = list(render_scenes(robot, params, args.test_scenes, args.seed + 100000, cfg.intrinsics, cfg.mount))
        results = evaluate(cfg, robot, test, clf)
        summary = {"model": str(args.out), "robot": robot.name, "training_scenes": args.scenes,
                   "seed": args.seed, "render_s": t1 - t0, "train_s": t2 - t1,
                   "block_px": clf.block_px, "stride_px": clf.cell_px, "dct_coefficients": clf.k,
                   "svm_c": cfg.classifier.svm_c, "ground_fraction": clf.ground_fraction,
                   "held_out": results}
        Path(str(args.out) + ".json").write_text(json.dumps(summary, indent=2) + "\n")
        print(f"trained on {args.scenes} rendered scenes ({t1 - t0:.0f} s rendering, {t2 - t1:.1f} s "
              f"training): {args.out}")
        _print(results)
        return 0
    if args.nav_command == "eval-perception":
        cfg, robot, params = _setup(args)
        clf = None
        if args.model:
            clf = BlockClassifier.load(args.model)
        frames = list(_counted(render_scenes(robot, params, args.scenes, args.seed, cfg.intrinsics, cfg.mount),
                               args.scenes, "nav eval-perception: rendering", not args.no_progress))
        _print(evaluate(cfg, robot, frames, clf))
        return 0
    if args.nav_command == "run":
        if not (math.isfinite(args.time_limit) and args.time_limit > 0):
            print(f"nav run: --time-limit: must be a finite number of seconds > 0, got {args.time_limit}",
                  file=sys.stderr)
            return 1
        try:
            world = load_world(args.world)
        except WorldError as e:
            print(str(e), file=sys.stderr)
            return 1
        try:
            run = NavRun(NavRunSpec(world, robot=args.robot, perception=args.perception, seed=args.seed,
                                    time_limit_s=args.time_limit, classifier=args.classifier,
                                    nav_config=args.config, flat_belly_fraction=args.flat_belly,
                                    pose_source=args.pose_source, depth_model=args.depth_model))
        except (ValueError, OSError) as e:      # a nav config, robot or classifier that cannot be used
            print(f"nav run: {e}", file=sys.stderr)
            return 1
        print(f"nav run: {world.name}, {args.robot}, {args.perception}, seed {args.seed}, up to "
              f"{args.time_limit:g} simulated s ...", file=sys.stderr, flush=True)
        bar = progress_bar(args.time_limit, f"nav run {world.name}", "sim s", enabled=not args.no_progress)
        try:
            result = run.run(progress=None if bar is None else lambda t_s: bar.update(t_s - bar.n))
        finally:
            if bar is not None:
                bar.close()
        result.write(args.out)
        print(json.dumps(result.metrics))
        return 0
    if args.nav_command == "experiment":
        return _experiment(args)
    if args.nav_command == "worlds":
        return _worlds(args)
    if args.nav_command == "ros-experiment":
        return _ros_experiment(args)
    print("usage: snake_autonomy nav {check-world FILE...|train-classifier --out FILE|eval-perception|run|"
          "experiment|worlds}",
          file=sys.stderr)
    return 2


def parse_seeds(text: str):
    """'0-4' -> [0..4]; '0,2,5' -> [0, 2, 5]."""
    try:
        if "-" in text.strip("-"):
            a, b = text.split("-", 1)
            seeds = list(range(int(a), int(b) + 1))
        else:
            seeds = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        seeds = []
    if not seeds:
        raise ValueError(f"--seeds: expected FIRST-LAST or a comma list of integers, got {text!r}")
    return seeds


def _experiment(args) -> int:
    seeds = parse_seeds(args.seeds)
    perceptions = ("depth", "mono") if args.perception == "both" else (args.perception,)
    if "mono" in perceptions and not args.classifier:
        print("nav experiment: perception mono/both needs --classifier FILE (snake_autonomy nav "
              "train-classifier --out FILE)", file=sys.stderr)
        return 1
    try:
        worlds = _chosen_worlds(args)
    except ValueError as e:
        print(f"nav experiment: {e}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    _write_worlds(worlds, out / "worlds")
    try:
        limits, factor = _time_limits(args, worlds)
    except ValueError as e:
        print(f"nav experiment: {e}", file=sys.stderr)
        return 1
    tasks = experiment_tasks(worlds, seeds, perceptions, robot=args.robot, time_limits_s=limits,
                             classifier=args.classifier, nav_config=args.config,
                             pose_source=args.pose_source, depth_model=args.depth_model,
                             out_dir=str(out / "runs") if args.keep_runs else None)
    t0 = time.perf_counter()
    with open_executor(args.engine, args.scheduler, args.workers) as ex:
        rows = run_tasks(ex, run_nav_task, tasks, desc=f"nav experiment {args.robot}",
                         progress=not args.no_progress)
    summary = summarise(rows)
    table = markdown_table(summary) + "\n\n" + outcome_table(summary) + "\n\n" + estimation_table(summary)
    write_csv(rows, out / "runs.csv")
    (out / "summary.json").write_text(json.dumps(
        {"robot": args.robot, "family": None if args.world_files else (args.family or "corridors"),
         "world_files": args.world_files, "worlds": [w.to_dict() for w in worlds], "seeds": seeds,
         "perceptions": list(perceptions), "pose_source": args.pose_source, "depth_model": args.depth_model,
         "time_limit": args.time_limit,
         "time_factor": factor,
         "time_limits_s": {w.name: limit for w, limit in zip(worlds, limits)}, "engine": args.engine,
         "wall_s": round(time.perf_counter() - t0, 1), "summary": summary}, indent=2) + "\n")
    (out / "table.md").write_text(table + "\n")
    print(table)
    print(f"\none run again, with its figures: snake_autonomy nav run --world {out / 'worlds'}/WORLD.yaml "
          f"--seed SEED [--perception ...] --out DIR (runs.csv: world, seed)")
    return 0


def _time_limits(args, worlds):
    """(per world: --time-limit S, or auto: --time-factor x its straight-line time at the follower's
    speed of the robot's nav config (runs/nav_experiment.py time_limit_s); the factor, None with S)."""
    if args.time_limit != "auto":
        try:
            limit = float(args.time_limit)
        except ValueError:
            raise ValueError(f"--time-limit: expected seconds or auto, got {args.time_limit!r}") from None
        if not (math.isfinite(limit) and limit > 0):
            raise ValueError(f"--time-limit: must be a finite number of seconds > 0, got {limit}")
        if args.time_factor is not None:
            raise ValueError(f"--time-factor {args.time_factor}: only with --time-limit auto")
        return [limit] * len(worlds), None
    factor = TIME_FACTOR if args.time_factor is None else args.time_factor
    if not (math.isfinite(factor) and factor > 0):
        raise ValueError(f"--time-factor: must be a finite number > 0, got {factor}")
    speed = NavConfig.from_yaml(args.config or nav_config_path(args.robot)).follower.speed_m_s
    return [time_limit_s(w, speed, factor) for w in worlds], factor


def _write_worlds(worlds, folder: Path, command: str = "nav experiment") -> None:
    """Each generated world as the world file `nav run --world` reads (folder/NAME.yaml): a row of
    runs.csv is reproduced without regenerating it."""
    folder.mkdir(parents=True, exist_ok=True)
    for w in worlds:
        (folder / f"{w.name}.yaml").write_text(
            f"# {w.source or w.name} (snake_autonomy {command})\n"
            + yaml.safe_dump(w.to_dict(), sort_keys=False))


WORLDS_CONVENTION = ("World indices: tune on worlds 0-19 (--first-world 0 --worlds 20); report on held-out "
                     "worlds from 100 up (--first-world 100), never looked at while tuning.")


def _generated(args, family: str):
    """generated_worlds of `family` for the parsed --first-world, --worlds and --robot."""
    return generated_worlds(family, args.first_world, args.worlds, args.robot)


def _chosen_worlds(args) -> list:
    """The worlds of --world-files GLOB, or of the generated --family (corridors by default)."""
    if args.world_files is None:
        return [w for w, _ in _generated(args, args.family or "corridors")]
    if args.family is not None:
        raise ValueError("--family and --world-files: one or the other")
    try:
        return world_files(args.world_files)
    except ValueError as e:
        raise ValueError(f"--world-files: {e}") from None


def _worlds(args) -> int:
    """nav worlds: the generated worlds as world files, with a top view each."""
    try:
        pairs = _generated(args, args.family)
    except ValueError as e:
        print(f"nav worlds: {e}", file=sys.stderr)
        return 1
    out = Path(args.out)
    _write_worlds([w for w, _ in pairs], out, "nav worlds")
    for w, layout in pairs:
        _top_view(w, layout, out / f"{w.name}.png")
        figures = "" if layout is None else (f", fill {layout.fill:.3f}, passage {layout.passage_m:.2f} m "
                                             f"(footprint {2 * layout.robot_clearance_m:.2f} m)")
        print(f"{out / w.name}.yaml: {len(w.obstacles)} obstacle(s), start {list(w.start)}, goal {list(w.goal)}"
              + figures)
    print(f"one through ROS: scripts/with-env roslaunch snake_autonomy sim.launch world:={out.resolve()}/NAME.yaml; "
          f"batch: snake_autonomy nav run --world {out}/NAME.yaml --out DIR")
    return 0


def _top_view(world, layout, path: Path) -> None:
    """Obstacles, the start (its heading an arrow, the body lying behind it dashed), the goal's disc."""
    import matplotlib  # lazy: matplotlib is heavy and only this path needs it
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon, Rectangle
    fig, ax = plt.subplots(figsize=(7, 6))
    if layout is not None:
        ax.add_patch(Rectangle(layout.origin_m, *layout.size_m, fill=False, ls=":", color="0.5", label="field"))
    for ob in world.obstacles:
        ax.add_patch(Circle((ob.x_m, ob.y_m), ob.radius_m, color="0.35") if ob.kind == "cylinder"
                     else Polygon(ob.corners(), color="0.35"))
    x, y, heading = world.start_rad
    if layout is not None:
        behind = layout.body_length_m
        ax.plot([x, x - behind * math.cos(heading)], [y, y - behind * math.sin(heading)], "b--", lw=1,
                label="body (lying straight)")
    ax.arrow(x, y, 0.4 * math.cos(heading), 0.4 * math.sin(heading), width=0.03, color="b", label="start")
    ax.add_patch(Circle(world.goal, world.goal_radius_m, color="g", alpha=0.5, label="goal"))
    title = f"{world.name}: {len(world.obstacles)} obstacles"
    if layout is not None:
        title += f", fill {100 * layout.fill:.0f} %, passage {layout.passage_m:.2f} m"
    ax.set_title(title)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.legend(loc="upper right", fontsize="small")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)


def _ros_experiment(args) -> int:
    """nav ros-experiment: the worlds (files or a generated family, as nav experiment) through
    sim.launch and in batch (runs/nav_ros_experiment.py)."""
    try:
        check_robot(args.robot)
        seeds = parse_seeds(args.seeds)
        if args.perception == "mono" and not args.classifier:
            raise ValueError("--perception mono needs --classifier FILE")
        worlds = _chosen_worlds(args)
        limits, _ = _time_limits(args, worlds)
    except ValueError as e:
        print(f"nav ros-experiment: {e}", file=sys.stderr)
        return 2
    out = Path(args.out)
    _write_worlds(worlds, out / "worlds", "nav ros-experiment")
    files = [str((Path(w.source) if args.world_files is not None else out / "worlds" / f"{w.name}.yaml").resolve())
             for w in worlds]
    t0 = time.perf_counter()
    bar = progress_bar(len(worlds) * len(seeds), "nav ros-experiment", "run", enabled=not args.no_progress)
    try:
        rows = run_experiment(list(zip(worlds, files)), seeds, out, limits, robot=args.robot,
                              perception=args.perception, classifier=args.classifier, nav_config=args.config,
                              on_run=bar.update if bar is not None else None)
    except RuntimeError as e:
        print(f"nav ros-experiment: {e}", file=sys.stderr)
        return 1
    finally:
        if bar is not None:
            bar.close()
    print(comparison_table(rows))
    print(f"\n{len(rows)} runs in {time.perf_counter() - t0:.0f} s: {out / 'table.md'}, {out / 'summary.json'}, "
          f"{out / 'runs'}/WORLD_sSEED/ (metrics.json, batch.json, roslaunch.log, log/)")
    return 0
