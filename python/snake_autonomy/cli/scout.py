"""`snake_autonomy scout`: the FBSR head-raising planner.

    snake_autonomy scout plan --robot ROBOT [--height-m H] [--max-active N] [--pipe X,Y,R] [--seed S] --out DIR
    snake_autonomy scout run  --robot ROBOT [same options] --out DIR

`plan` writes DIR/plan.json (plan_io.py) and the figures DIR/zmp_stages.png, DIR/head_height.png,
and DIR/trajectory.json: the points of the driver's trajectory_msgs/JointTrajectory (trajectory.py;
refused with exit 1 when they exceed config/driver.yaml's max_joint_velocity_rad_s). With --lower
these are the inverse plan's, from the raised posture back down to the lying one.
`run` also executes the plan in the MuJoCo plant (execute.py) and writes DIR/metrics.json, plus
DIR/run.json (head position, base lift, pipe distance). Without --height-m the head goes as high as
the active portion allows; with it, planning stops once the head reaches H. Bad options (unknown
robot, a height no plan reaches, a pipe inside the robot or out of reach, a negative seed, a bad
--config file) end with one message and exit 1, before planning. While planning, a bar on stderr
counts the stages planned (--no-progress: none).

Exit status (EXIT_STATUS): 0 done and, for `run`, metrics.json's outcome "ok"; 1 bad options or
files; 2 usage; 3 `run` executed the plan but the robot tipped in physics, the head ended outside
the pipe's bore, or more than 3 cm below the planned height (outcome "tipped" / "missed_pipe" /
"missed_height"; the reason on one line, metrics.json written).
"""
import json
import math
import sys
from pathlib import Path

from snake_autonomy.paths import config_path
from snake_autonomy.planning.fbsr import plan_io
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.cost import Pipe
from snake_autonomy.planning.fbsr.figures import write_figures
from snake_autonomy.planning.fbsr.planner import lowering
from snake_autonomy.planning.fbsr.stage import PlanningError
from snake_autonomy.planning.fbsr.trajectory import driver_velocity_limit, lead_in_s, plan_points, velocity_problems
from snake_autonomy.runs.scout_execute import run_plan
from snake_autonomy.runs.sweep_runner import progress_bar
from snake_autonomy.sim.config import servo_torque_limit_nm


EXIT_STATUS = ("exit status: 0 the run is ok; 1 bad options or files; 2 usage; 3 the robot tipped, missed the "
               "pipe or ended below the planned height in physics (metrics.json outcome tipped / missed_pipe / "
               "missed_height, the reason on one line)")
OUTCOME_NOT_OK = 3
PIPE_REACH_M = 2.0          # |x|, |y| of the pipe's axis: no robot of config/robots/ is longer
PIPE_RADIUS_MAX_M = 0.5
SEED_MAX = 2 ** 32 - 1


def _pipe(text):
    """The --pipe option as a Pipe: three finite numbers, the axis within PIPE_REACH_M of the tail in
    x and y, the radius in (0, PIPE_RADIUS_MAX_M]; ValueError naming the option and value."""
    try:
        x, y, r = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--pipe: expected X,Y,R in metres (e.g. 0.1,0.3,0.06), got {text!r}") from None
    if not all(math.isfinite(v) for v in (x, y, r)):
        raise ValueError(f"--pipe {text}: X, Y and R must be finite numbers of metres")
    if max(abs(x), abs(y)) > PIPE_REACH_M:
        raise ValueError(f"--pipe {text}: the axis must be within {PIPE_REACH_M:g} m of the tail in x and y, "
                         f"got x {x:g}, y {y:g}")
    if not 0 < r <= PIPE_RADIUS_MAX_M:
        raise ValueError(f"--pipe {text}: R must be in (0, {PIPE_RADIUS_MAX_M:g}] m, got {r:g}")
    return Pipe(x, y, r)


def _seed(option, text):
    """A seed option's value: an integer in 0..SEED_MAX; ValueError naming the option otherwise."""
    try:
        value = int(text)
    except (TypeError, ValueError):
        value = -1
    if not 0 <= value <= SEED_MAX:
        raise ValueError(f"{option} {text}: must be an integer in 0..{SEED_MAX}")
    return value


class _StageBar:
    """Counts each stage the planner adds to its plan (raise, shift, lower) on a bar on stderr, named
    with its kind and active modules. The bar appears with the first stage: a plan refused before any
    (a pipe inside the lying robot) prints its one message only."""

    def __init__(self, planner, desc: str, enabled: bool):
        self.bar, self.desc = None, desc
        if enabled:
            planner.on_stage = self._count

    def _count(self, stage) -> None:
        if self.bar is None:
            self.bar = progress_bar(None, self.desc, "stage")
        self.bar.set_postfix_str(f"{stage.kind}, {stage.active_modules} active", refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def add_arguments(parser):
    sub = parser.add_subparsers(dest="scout_command", metavar="SCOUT_COMMAND")
    for name, help_text in (("plan", "plan a head-raising trajectory (plan.json + figures)"),
                            ("run", "plan, then execute it in the MuJoCo plant (metrics.json)")):
        p = sub.add_parser(name, help=help_text, description=help_text, epilog=EXIT_STATUS)
        p.add_argument("--robot", required=True, help="robot name under config/robots/ or a YAML path")
        p.add_argument("--height-m", type=float, metavar="H", help="end condition: head height (m)")
        p.add_argument("--max-active", type=int, metavar="N",
                       help="most active modules (default: the robot's in config/scout.yaml)")
        p.add_argument("--pipe", metavar="X,Y,R",
                       help="vertical pipe: axis x, y and inner radius (m); a negative x: --pipe=-0.1,0.3,0.06")
        p.add_argument("--seed", default="0", metavar="S", help=f"planner seed, 0..{SEED_MAX}")
        p.add_argument("--out", required=True, metavar="DIR", help="results folder")
        p.add_argument("--no-restarts", action="store_true", help="no random restarts (benchmarks)")
        p.add_argument("--config", metavar="YAML", help="planner configuration (default config/scout.yaml)")
        p.add_argument("--no-progress", action="store_true",
                       help="no progress bar (planned stages, on stderr)")
        if name == "plan":
            p.add_argument("--lower", action="store_true",
                           help="write the inverse: from the raised posture back to the lying one")
        if name == "run":
            p.add_argument("--sim-seed", default="0", metavar="S",
                           help=f"physics draws of config/sim.yaml, 0..{SEED_MAX}")


def main(args) -> int:
    if args.scout_command is None:
        print("usage: snake_autonomy scout {plan,run} --robot ROBOT --out DIR [options]", file=sys.stderr)
        return 2
    try:
        pipe = _pipe(args.pipe) if args.pipe else None
        seed = _seed("--seed", args.seed)
        sim_seed = _seed("--sim-seed", args.sim_seed) if args.scout_command == "run" else 0
        if args.height_m is not None and not args.height_m > 0:
            raise ValueError(f"--height-m {args.height_m}: must be > 0")
        planner, cfg = build_planner(args.robot, args.config, torque_limit_nm=servo_torque_limit_nm())
        reach = planner.robot.head_length_m + planner.robot.num_joints * planner.robot.link_length_m
        if args.height_m is not None and args.height_m > reach:
            raise ValueError(f"--height-m {args.height_m}: no plan reaches it, {planner.robot.name} "
                             f"is {reach:.2f} m long")
        if pipe is not None and math.hypot(pipe.x_m, pipe.y_m) > reach:
            raise ValueError(f"--pipe {args.pipe}: the axis is {math.hypot(pipe.x_m, pipe.y_m):.2f} m from the "
                             f"tail, beyond the {reach:.2f} m length of {planner.robot.name}")
        bar = _StageBar(planner, f"scout {args.scout_command}: planning", not args.no_progress)
        try:
            plan = planner.plan(max_active=args.max_active, height_m=args.height_m, pipe=pipe,
                                seed=seed, restarts=not args.no_restarts)
        except PlanningError as err:
            if args.height_m is None or str(err).startswith("--height-m"):
                raise
            raise PlanningError(f"--height-m {args.height_m}: no plan reaches it ({err})") from None
        finally:
            bar.close()
    except (ValueError, FileNotFoundError, PlanningError) as err:
        print(f"scout {args.scout_command}: {err}", file=sys.stderr)
        return 1

    chain = planner.chain
    vmax = driver_velocity_limit()
    if getattr(args, "lower", False):
        raised_s = plan.planning_time_s
        plan = lowering(plan)
        plan.planning_time_s = raised_s
        trajectory = plan_points(plan, cfg.planner.sample_period_s)
    else:
        trajectory = plan_points(plan, cfg.planner.sample_period_s, lead_in_s(chain.lower, chain.upper, vmax))
    problems = velocity_problems(trajectory, vmax)
    if problems:
        print(f"scout {args.scout_command}: the trajectory breaks the driver's limit: {'; '.join(problems)}",
              file=sys.stderr)
        return 1
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    period = cfg.planner.sample_period_s
    doc = plan_io.write(plan, out / "plan.json", period)
    write_figures(plan, out, period, pipe)
    (out / "trajectory.json").write_text(json.dumps(trajectory.to_dict()) + "\n")
    print(f"{plan.robot_name}: {plan.active_modules} active modules, head {plan.final_head_height_m:.3f} m, "
          f"{len(plan.stages)} stages, {plan.duration_s:.1f} s of motion, {plan.restarts} restarts, "
          f"planned in {plan.planning_time_s:.1f} s -> {out / 'plan.json'} ({len(doc['samples'])} samples)")
    if args.scout_command != "run":
        return 0

    result = run_plan(plan, config_path("sim.yaml"), sim_seed, pipe, period)
    (out / "metrics.json").write_text(json.dumps(result["metrics"], indent=2) + "\n")
    (out / "run.json").write_text(json.dumps(result["extra"], indent=2) + "\n")
    m = result["metrics"]
    line = (f"physics: {m['outcome']}, tipped {m['tipped']}, CoP inside {m['cop_inside_fraction']:.3f}, head "
            f"{m['final_head_height_m']:.3f} m (planned {m['planned_head_height_m']:.3f}), "
            f"max torque {100 * m['max_torque_ratio']:.0f} % of the limit")
    extra = result["extra"]
    if "base_load_fraction" in extra:
        line += (f", base carried {100 * extra['base_load_fraction']:.0f} % of the weight (modules planned in the "
                 f"air {100 * extra['air_load_fraction']:.0f} %), CoM at least "
                 f"{1000 * extra['min_com_margin_m']:.0f} mm inside the base's contacts")
    if pipe is not None:
        line += (f", head {'inside' if extra.get('head_in_bore') else 'not inside'} the bore, "
                 f"{extra['head_to_pipe_axis_m']:.3f} m from the pipe axis (bore {extra['bore_limit_m']:.3f} m)")
    print(line + f" -> {out / 'metrics.json'}")
    if m["outcome"] != "ok":
        print(f"scout run: {result['extra']['reason']}", file=sys.stderr)
        return OUTCOME_NOT_OK
    return 0
