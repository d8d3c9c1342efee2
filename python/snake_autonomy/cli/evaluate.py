"""`snake_autonomy evaluate REF EST`: statistics like evo_ape/evo_rpe, plus yaw alignment, tracking
loss, per-segment tables, plots and a one-page report. Errors print one message and exit 1."""
import argparse
import os
import sys
from pathlib import Path

import numpy as np

from snake_autonomy.evaluation.alignment import ALIGN_MODES
from snake_autonomy.evaluation.errors import EvaluationError
from snake_autonomy.evaluation.metrics import RELATIONS, EvaluationOptions, evaluate
from snake_autonomy.evaluation.readers import FORMATS, LOST_COVARIANCE, bag_topics, guess_format, load_trajectory
from snake_autonomy.evaluation.report import format_table, write_json, write_outputs
from snake_autonomy.evaluation.segments import SEGMENT_KEYS, STATUS_TOPIC, read_tracking_status

EPILOG = """examples:
  snake_autonomy evaluate gt.txt est.txt --align se3
  snake_autonomy evaluate mono_gt.txt mono_kf.txt --align sim3 --json out.json
  snake_autonomy evaluate V102_groundtruth.csv V102.txt --align se3           (EuRoC CSV: by extension)
  snake_autonomy evaluate run.bag run.bag --ref-topic /optitrack/head --est-topic /rtabmap/odom \\
      --align yaw --t-max-diff 0.02 --plots results/run1      (segments from /tracking_status in the bag)
  snake_autonomy evaluate run.bag run.bag --ref-topic /tf:world.head_mocap --est-topic /tf:odom.head
  snake_autonomy evaluate gt.txt est.txt --metric rpe --delta 1 --delta-unit m --relation angle_deg
formats are guessed from the extension (.bag: bag, .csv: euroc, else tum) unless given."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.epilog = EPILOG
    parser.add_argument("ref", metavar="REF", help="reference (ground truth): TUM file, EuRoC CSV or ROS 1 bag")
    parser.add_argument("est", metavar="EST", help="estimate: TUM file, EuRoC CSV or ROS 1 bag")
    inputs = parser.add_argument_group("inputs")
    inputs.add_argument("--ref-format", choices=FORMATS, help="format of REF (default: from its extension)")
    inputs.add_argument("--est-format", choices=FORMATS, help="format of EST (default: from its extension)")
    inputs.add_argument("--ref-topic", help="bag topic of REF: PoseStamped, Odometry, or /tf:[PARENT.]CHILD")
    inputs.add_argument("--est-topic", help="bag topic of EST: PoseStamped, Odometry, or /tf:[PARENT.]CHILD")
    algo = parser.add_argument_group("metric (evo's meaning and defaults)")
    algo.add_argument("--metric", choices=("ape", "rpe"), default="ape", help="absolute or relative pose error")
    algo.add_argument("--relation", choices=tuple(RELATIONS), default="trans",
                      help="which part of the pose error: trans (m), angle_deg, ...")
    algo.add_argument("--align", choices=ALIGN_MODES, default="none",
                      help="none, se3/sim3 (Umeyama), origin, or yaw (4-DoF: yaw + translation)")
    algo.add_argument("--n-to-align", type=int, default=-1, metavar="N",
                      help="align on the first N pairs only (-1: all)")
    algo.add_argument("--t-max-diff", type=float, default=0.01, metavar="S",
                      help="association window in seconds")
    algo.add_argument("--t-offset", type=float, default=0.0, metavar="S",
                      help="added to the estimate's stamps before association")
    algo.add_argument("--sync", choices=("nearest", "interpolation"), default="nearest",
                      help="associate nearest stamps or interpolate the denser trajectory")
    algo.add_argument("--delta", type=float, default=1.0, metavar="N", help="RPE step")
    algo.add_argument("--delta-unit", choices=("f", "m"), default="f", help="RPE step in frames (f) or metres (m)")
    algo.add_argument("--all-pairs", action="store_true", help="RPE: all pairs, not only consecutive ones")
    loss = parser.add_argument_group("tracking loss and segments")
    loss.add_argument("--max-gap", type=float, default=None, metavar="S",
                      help="estimate stamps further apart than S seconds are a tracking loss "
                           "(0: off; default: max(1 s, 20 median periods); negative: refused)")
    loss.add_argument("--lost-covariance", type=float, default=LOST_COVARIANCE, metavar="C",
                      help="Odometry covariance at or above C means lost (the default is RTAB-Map's)")
    loss.add_argument("--keep-loss", action="store_true",
                      help="flag tracking loss but keep its pairs in alignment and statistics")
    loss.add_argument("--status-bag", metavar="BAG",
                      help="bag with the tracker's TrackingStatus (default: EST or REF if a bag holds it)")
    loss.add_argument("--status-topic", default=STATUS_TOPIC, help="the tracker's TrackingStatus topic")
    loss.add_argument("--segment-by", action="append", choices=SEGMENT_KEYS,
                      help="segment tables to print (repeatable; default: all of gait, leg, mode)")
    out = parser.add_argument_group("outputs")
    out.add_argument("--json", metavar="OUT", help="write the statistics and details as JSON")
    out.add_argument("--plots", metavar="DIR", help="write PNG plots and the one-page report (PDF+PNG) here")
    out.add_argument("--quiet", action="store_true", help="do not print the table")


def options_from_args(args) -> EvaluationOptions:
    return EvaluationOptions(
        metric=args.metric, relation=args.relation, align=args.align, n_to_align=args.n_to_align,
        t_max_diff_s=args.t_max_diff, t_offset_s=args.t_offset, sync=args.sync, delta=args.delta,
        delta_unit=args.delta_unit, all_pairs=args.all_pairs, max_gap_s=args.max_gap,
        exclude_loss=not args.keep_loss, segment_keys=tuple(args.segment_by or SEGMENT_KEYS))


def run(args) -> int:
    options = options_from_args(args)
    options.validate()
    if not (np.isfinite(args.lost_covariance) and args.lost_covariance > 0):
        raise EvaluationError(f"--lost-covariance: must be a positive number, got {args.lost_covariance}")
    _check_output_paths(args)
    ref = load_trajectory(args.ref, args.ref_format, args.ref_topic, args.lost_covariance)
    est = load_trajectory(args.est, args.est_format, args.est_topic, args.lost_covariance)
    for warning in ref.warnings + est.warnings:
        print(f"snake_autonomy evaluate: warning: {warning}", file=sys.stderr)
    status = _status(args)
    result = evaluate(ref, est, options, status=status)
    if not args.quiet:
        print(format_table(result))
    if args.json:
        write_json(result, args.json)
    if args.plots:
        paths = write_outputs(result, args.plots, json_path=args.json)
        if not args.quiet:
            print(f"\nwrote {len(paths)} files to {args.plots}")
    return 0


def _check_output_paths(args) -> None:
    """Creates the output folders now, so an unwritable path fails before the work, in one line."""
    targets = [("--plots", Path(args.plots))] if args.plots else []
    if args.json:
        targets.append(("--json", Path(args.json).parent))
        if Path(args.json).is_dir():
            raise EvaluationError(f"--json {args.json}: is a folder; give a file name")
    for option, folder in targets:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise EvaluationError(f"{option}: cannot create the folder {folder}: {exc.strerror or exc}") from None
        if not os.access(folder, os.W_OK):
            raise EvaluationError(f"{option}: cannot write into {folder}: permission denied")


def _status(args):
    if args.status_bag:
        return read_tracking_status(args.status_bag, args.status_topic)
    topic = args.status_topic
    for path, fmt in ((args.est, args.est_format), (args.ref, args.ref_format)):
        if (fmt or guess_format(path)) != "bag":
            continue
        topics = bag_topics(path)
        if topic in topics or "/" + topic.lstrip("/") in topics or topic.lstrip("/") in topics:
            return read_tracking_status(path, topic)
    return None


def main(args) -> int:
    try:
        return run(args)
    except EvaluationError as exc:
        print(f"snake_autonomy evaluate: error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:   # an output that could not be written after all (disk full, removed folder)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"snake_autonomy evaluate: error: cannot write {where}{exc.strerror or exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        os._exit(1)
