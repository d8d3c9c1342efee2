"""`snake_autonomy calibrate`: the steering offset (thesis eq. 3.31) and the heading offset, on the
simulated robot or on the robot through ROS; one sequence, one analysis.

    snake_autonomy calibrate --sim --seeds 0-4 --out results/calibration/sim
    snake_autonomy calibrate --ros --out results/calibration/cobra     # driver_node + pose source running

Both run open-loop sidewinding at each --deltas value (settling cycles, then recorded cycles; the
gait command re-sent as a heartbeat), hold the robot at the end, on Ctrl-C and on a stale pose, fit
the turn rate against δ (δ_offset = -K_bias <θ̇_drift>) and the direction of travel against the
virtual chassis, and write OUT/calibration.yaml (a `tracker:` block: never applied by itself) and
OUT/calibration.png. Exit 0 with a calibration, 1 when the run or the fit failed, 2 on a usage error.
"""
import math
import sys
from pathlib import Path
from typing import List

from snake_autonomy import _core
from snake_autonomy.calibration.analysis import CalibrationError, fit
from snake_autonomy.calibration.output import plot, tracker_block, write_yaml
from snake_autonomy.calibration.ros_backend import connect
from snake_autonomy.calibration.sequence import Plan, run_plan
from snake_autonomy.calibration.sim_backend import SimRobot
from snake_autonomy.paths import config_path
from snake_autonomy.runs.mission_experiment import parse_seeds
from snake_autonomy.safe_yaml import short_repr

DEFAULT_DELTAS = "0,5,10,15"


def add_arguments(parser):
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--sim", action="store_true", help="the simulated robot (batch simulator, no ROS)")
    where.add_argument("--ros", action="store_true", help="the robot through ROS (driver_node must be running)")
    parser.add_argument("--out", required=True, metavar="DIR", help="calibration.yaml and calibration.png go here")
    parser.add_argument("--deltas", default=DEFAULT_DELTAS, help="steering values, degrees")
    parser.add_argument("--gait", default="sidewind", help="the steerable gait")
    parser.add_argument("--settle-cycles", type=float, default=3.0,
                        help="gait cycles after each new delta, not recorded")
    parser.add_argument("--cycles", type=int, default=6, help="gait cycles recorded per delta")
    root = config_path()
    parser.add_argument("--gaits", default=str(root / "gaits.yaml"), help="gait library (its period; the driver's)")
    parser.add_argument("--pose-timeout", type=float, default=0.5, metavar="S", help="stale pose: hold")
    sim = parser.add_argument_group("--sim")
    sim.add_argument("--seeds", default="0-1", help="randomised physics, e.g. 0-4 or 0,3")
    sim.add_argument("--feedback", choices=("mocap", "vio"), default="mocap", help="the pose source")
    sim.add_argument("--sim-config", default=str(root / "sim.yaml"), help="simulated robot")
    ros = parser.add_argument_group("--ros")
    ros.add_argument("--command-topic", default="gait_command", help="the driver's gait command topic")
    ros.add_argument("--pose-topic", default="com_pose", help="the driver's CoM + virtual chassis pose")
    ros.add_argument("--start-timeout", type=float, default=5.0, metavar="S", help="wait this long for a first pose")


def main(args) -> int:
    try:
        deltas = parse_deltas(args.deltas)
        period_s = 1.0 / _core.GaitLibrary.from_yaml(args.gaits).frequency_hz(args.gait)
        seeds = parse_seeds(args.seeds) if args.sim else []
        Plan(deltas, period_s, args.gait, args.settle_cycles, args.cycles).check()
    except (ValueError, RuntimeError) as exc:
        print(f"snake_autonomy calibrate: {exc}", file=sys.stderr)
        return 2
    plans = ([Plan(deltas, period_s, args.gait, args.settle_cycles, args.cycles, run=f"seed {s}") for s in seeds]
             if args.sim else [Plan(deltas, period_s, args.gait, args.settle_cycles, args.cycles, run="robot")])
    segments, stopped = (_sim(args, plans, seeds) if args.sim else _ros(args, plans[0]))
    if stopped:
        print(f"warning: the run stopped early: {'; '.join(stopped)}", file=sys.stderr)
    try:
        result = fit(segments)
    except CalibrationError as exc:
        print(f"snake_autonomy calibrate: no calibration: {exc}", file=sys.stderr)
        return 1
    out = Path(args.out)
    source = {"backend": "sim" if args.sim else "ros", "gait": args.gait, "gaits": args.gaits,
              "period_s": period_s, "deltas_deg": deltas, "settle_cycles": args.settle_cycles,
              "record_cycles": args.cycles, "runs": [p.run for p in plans], "stopped": stopped}
    if args.sim:
        source.update(seeds=seeds, feedback=args.feedback, sim_config=args.sim_config)
    path = write_yaml(out / "calibration.yaml", result, source)
    png = plot(out / "calibration.png", result, title=f"{args.gait}, {', '.join(p.run for p in plans)}")
    print(result.summary())
    block = tracker_block(result)
    print(f"\nwrote {path} and {png}. Not applied: to use it, run the mission with\n"
          f"  roslaunch snake_autonomy mission.launch tracker_overrides:={path}\n"
          f"or merge into the tracker: section of config/sim.yaml (simulated robot) / config/tracker.yaml (robot):\n"
          f"  tracker:\n" + "".join(f"    {k}: {v}\n" for k, v in block.items()))
    return 0


def parse_deltas(text: str) -> List[float]:
    """--deltas '0,5,10' -> [0.0, 5.0, 10.0]; ValueError naming --deltas and the value otherwise."""
    try:
        deltas = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(f"--deltas: expected degrees separated by commas, got {short_repr(text)}") from None
    if not all(math.isfinite(d) for d in deltas):
        raise ValueError(f"--deltas: must be finite, got {short_repr(text)}")
    if len(set(deltas)) < 2:
        raise ValueError(f"--deltas: need two different values or more, got {short_repr(text)}")
    return deltas


def _sim(args, plans, seeds):
    segments, stopped = [], []
    for seed, plan in zip(seeds, plans):
        robot = SimRobot(seed=seed, feedback=args.feedback, sim_config=args.sim_config, gaits=args.gaits)
        outcome = run_plan(robot, plan, pose_timeout_s=args.pose_timeout, log=lambda m, s=seed: print(f"seed {s}: {m}"))
        segments += outcome.segments
        if outcome.stopped:
            stopped.append(f"seed {seed}: {outcome.stopped}")
        for seg in outcome.segments:
            print(f"seed {seed}: delta {seg.delta_deg:+g} deg recorded, {len(seg.samples)} poses, "
                  f"{math.hypot(*(seg.samples[-1, 1:3] - seg.samples[0, 1:3])):.2f} m travelled")
    return segments, stopped


def _ros(args, plan):
    import rosgraph  # lazy: ROS only on this path; the module is imported without ROS too
    import rospy

    if not rosgraph.is_master_online():
        print("snake_autonomy calibrate: no ROS master (start the driver and the pose source first)", file=sys.stderr)
        return [], ["no ROS master"]
    rospy.init_node("calibrate", anonymous=True, disable_signals=True)   # Ctrl-C: hold first, then exit
    try:
        robot = connect(args.command_topic, args.pose_topic)
    except RuntimeError as exc:
        print(f"snake_autonomy calibrate: {exc}", file=sys.stderr)
        return [], [str(exc)]
    outcome = run_plan(robot, plan, pose_timeout_s=args.pose_timeout, start_timeout_s=args.start_timeout,
                       log=rospy.loginfo)
    rospy.sleep(0.2)                # let the hold go out before the node goes
    rospy.signal_shutdown("calibration done")
    return outcome.segments, [outcome.stopped] if outcome.stopped else []
