"""snake_autonomy.evaluation: a state estimate against ground truth (thesis 4.1), with evo as the engine.

Association, Umeyama alignment and APE/RPE are evo's; this package adds what VIO on a snake needs:
yaw-only (4-DoF) alignment, tracking-loss intervals kept out of the statistics and shaded on the
plots, per-segment statistics (gait, mission leg, tracker mode) from the logger's TrackingStatus,
the thesis's plots and a one-page report.

Command line: ``snake_autonomy evaluate REF EST [options]`` (``snake_autonomy evaluate --help``).

Python API (what the simulator calls after a mission)::

    from snake_autonomy.evaluation import (EvaluationOptions, evaluate, load_trajectory,
                                           trajectory_from_arrays, write_outputs)

    ref = load_trajectory("run.bag", "bag", "/optitrack/head")      # or trajectory_from_arrays(...)
    est = load_trajectory("run.bag", "bag", "/rtabmap/odom")        # Odometry: 9999 covariance = lost
    result = evaluate(ref, est, EvaluationOptions(align="yaw", t_max_diff_s=0.02),
                      status=read_tracking_status("run.bag"))        # status optional: segments
    print(format_table(result))          # evo's table + pairs, loss, per-segment tables
    result.stats["rmse"], result.pairs, result.loss_intervals, result.segments
    write_outputs(result, "results/run_0001/evaluation")   # stats.json, *.png, report.pdf/png

``trajectory_from_arrays(stamps_s, xyz, quat_xyzw)`` builds an input from arrays (e.g. the
simulator's ground truth); rows that are null poses are dropped and reported as tracking loss.
Every user-fixable problem raises ``EvaluationError`` with a message; the CLI prints it and exits 1.

Files: readers.py (TUM, EuRoC, bag topics/TF), alignment.py (yaw-only + dispatch), metrics.py
(options, evaluate, result), stats.py (evo's statistics), tracking_loss.py, segments.py (TrackingStatus),
plots.py, report.py; the command line: cli/evaluate.py.
"""
from .alignment import ALIGN_MODES, yaw_alignment
from .errors import EvaluationError
from .metrics import EvaluationOptions, EvaluationResult, evaluate
from .readers import LoadedTrajectory, bag_topics, load_trajectory, trajectory_from_arrays
from .report import format_table, write_json, write_outputs
from .segments import StatusSample, read_tracking_status
from .stats import statistics
from .tracking_loss import LossInterval

__all__ = [
    "ALIGN_MODES", "EvaluationError", "EvaluationOptions", "EvaluationResult", "LoadedTrajectory",
    "LossInterval", "StatusSample", "bag_topics", "evaluate", "format_table", "load_trajectory",
    "read_tracking_status", "statistics", "trajectory_from_arrays", "write_json", "write_outputs",
    "yaw_alignment",
]
