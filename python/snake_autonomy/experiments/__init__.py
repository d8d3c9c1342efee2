"""snake_autonomy.experiments: run logging (bag + metrics) and the results folder.

- :func:`write_results` / :func:`compute_metrics`: plain arrays in, results folder out (no ROS);
  the simulator's batch runs use them too.
- :class:`RunLog`: the bag and the up-to-date metrics of a run (rosbag, no master).
- :func:`read_run` / :func:`report_from_bag`: a bag (also an unindexed one from a killed run) back
  to arrays / to the results folder (``snake_autonomy report BAG --out DIR``).
"""
from .results import compute_metrics, normalise_decisions, segments, write_results

__all__ = ["write_results", "compute_metrics", "normalise_decisions", "segments", "RunLog", "read_run",
           "report_from_bag"]


def __getattr__(name):   # rosbag-dependent parts load on first use
    if name == "RunLog":
        from .run_log import RunLog
        return RunLog
    if name in ("read_run", "report_from_bag"):
        from . import bag_io
        return getattr(bag_io, name)
    raise AttributeError(name)
