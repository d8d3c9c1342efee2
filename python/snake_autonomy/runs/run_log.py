"""The log of one run: a rosbag of the topics that matter (RunBag) plus a metrics file kept up to date (RunLog,
a mission run; a navigation run: runs/nav_record.py).

ROS-free apart from rosbag (no master needed), so the killed-run behaviour is testable in a plain
process. Crash safety:

- the bag is flushed (its open chunk closed and written) after every tracker decision, so a run
  killed with SIGKILL leaves a bag that reindexes to everything up to the last decision;
- metrics.json is rewritten atomically after every decision (outcome "running" until the end, with
  ``updated_at`` and a ``note`` saying that a process that died leaves it there and that
  ``snake_autonomy report BAG`` rebuilds the final figures, marking the run ``interrupted``);
- ``close(outcome)`` (end, abort, time-out, SIGINT/SIGTERM) writes the bag's index and the full
  results folder from the closed bag: the same code path as ``snake_autonomy report BAG``.
"""
import json
import threading
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

from snake_autonomy.runs.bag_io import RUN_TOPIC, report_from_bag
from snake_autonomy.runs.results import PathLength, compute_metrics, write_json_atomic

BAG_NAME = "run.bag"
LIVE_NOTE = ("written while the run was live; if the process died this is where it stopped: "
             "snake_autonomy report BAG rebuilds the final figures")


def _to_time(t_s: float):
    import genpy  # lazy: ROS only on this path; the module is imported without ROS too
    return genpy.Time.from_sec(t_s)


class RunBag:
    """A run's bag: the run's events (JSON on RUN_TOPIC) and recorded messages, thread-safe, flushed on
    request; close_bag() writes the end event and the index. The mission's RunLog and the navigation
    recorder (runs/nav_record.py) each add their metrics on top."""

    def __init__(self, run_dir, t_start_s: float):
        import rosbag  # lazy: ROS only on this path; the module is imported without ROS too
        from std_msgs.msg import String
        self._String = String
        self.run_dir = Path(run_dir)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        self.bag_path = self.run_dir / BAG_NAME
        self.t_start_s = float(t_start_s)
        self._lock = threading.Lock()
        self._bag = rosbag.Bag(str(self.bag_path), "w")
        self._last_t = self.t_start_s
        self.closed = False

    def _event(self, event: Dict[str, Any], t_s: float) -> None:
        with self._lock:
            if self._bag is not None:
                self._bag.write(RUN_TOPIC, self._String(data=json.dumps(event)), _to_time(t_s))

    def event(self, event: Dict[str, Any], t_s: float) -> None:
        """A run event (JSON on the run topic), e.g. {"event": "scout", ...}: read back by bag_io."""
        self._event(event, t_s)

    def write(self, topic: str, msg, t_s: float) -> None:
        """Records one message (thread-safe; ignored after close)."""
        with self._lock:
            if self._bag is None:
                return
            self._bag.write(topic, msg, _to_time(t_s))
            self._last_t = max(self._last_t, t_s)

    def flush(self) -> None:
        with self._lock:
            if self._bag is not None:
                self._bag.flush()
                self._bag._file.flush()   # rosbag keeps a buffered file object: push it to the OS

    def close_bag(self, outcome: str, t_s: Optional[float] = None) -> float:
        """Writes the end event and the bag's index; the end time. The caller sets self.closed first."""
        t_end = t_s if t_s is not None else self._last_t
        self._event({"event": "end", "outcome": outcome, "t": t_end}, max(t_end, self._last_t))
        with self._lock:
            bag, self._bag = self._bag, None
            bag.close()
        return t_end


class RunLog(RunBag):
    def __init__(self, run_dir, mission_name: str, waypoints: Sequence[Sequence[float]], t_start_s: float,
                 mission_yaml: str = "", tracker: Optional[Dict[str, Any]] = None,
                 extra: Optional[Dict[str, Any]] = None):
        super().__init__(run_dir, t_start_s)
        self.metrics_path = self.run_dir / "metrics.json"
        self.waypoints = [tuple(float(v) for v in w) for w in waypoints]
        self.tracker = dict(tracker or {})
        self._decisions: Dict[str, List[Any]] = {k: [] for k in (
            "t", "waypoint_index", "target_index", "reached", "distance", "yaw_error_abs", "yaw_error_rel",
            "yaw_error", "pose_stale")}
        self._path = PathLength()
        self.meta = {"mission": mission_name, "t_start": self.t_start_s, "waypoints": self.waypoints,
                     "tracker": self.tracker, "mission_yaml": mission_yaml,
                     "wall_time_start": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        self.meta.update(extra or {})
        self._event({"event": "start", **self.meta}, self.t_start_s)
        (self.run_dir / "mission.yaml").write_text(mission_yaml or "")
        self._write_metrics("running")

    def add_pose(self, t_s: float, x: float, y: float) -> None:
        """The centre of mass, for the running path length of the metrics (results.PathLength)."""
        self._path.add(x, y)

    @property
    def path_length_m(self) -> float:
        return self._path.length_m

    def add_decision(self, t_s: float, waypoint_index: int, target_index: int, reached: bool, distance: float,
                     yaw_error_abs: float, yaw_error_rel: float, yaw_error: float, pose_stale: bool = False):
        """One tracker step: flushes the bag to disk, then updates metrics.json. Ignored after close()
        (a decision racing the shutdown must not turn the final metrics back into "running")."""
        if self.closed:
            return
        for k, v in (("t", t_s), ("waypoint_index", waypoint_index), ("target_index", target_index),
                     ("reached", reached), ("distance", distance), ("yaw_error_abs", yaw_error_abs),
                     ("yaw_error_rel", yaw_error_rel), ("yaw_error", yaw_error), ("pose_stale", pose_stale)):
            self._decisions[k].append(v)
        self._last_t = max(self._last_t, t_s)
        # the bag first: metrics.json must never count a decision the bag on disk does not hold (a
        # kill between the two left metrics at 5 decisions and the bag at 4, test_run_log)
        self.flush()
        self._write_metrics("running")

    def metrics(self, outcome: str) -> Dict[str, Any]:
        return compute_metrics(self.waypoints, self._decisions, None, outcome, self.t_start_s,
                               extra={"path_length_m": self._path.length_m, "duration_s": self._last_t - self.t_start_s,
                                      "meta": {k: v for k, v in self.meta.items() if k != "mission_yaml"}})

    def _write_metrics(self, outcome: str) -> None:
        metrics = self.metrics(outcome)
        metrics["updated_at"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        if outcome == "running":
            metrics["note"] = LIVE_NOTE.replace("BAG", str(self.bag_path))
        write_json_atomic(self.metrics_path, metrics)

    def close(self, outcome: str, t_s: Optional[float] = None, plots: bool = True) -> Dict[str, Path]:
        """Ends the run: closes the bag (writes its index) and writes the results folder.
        Safe to call twice (the second call does nothing)."""
        if self.closed:
            return {}
        self.closed = True
        self.close_bag(outcome, t_s)
        self._write_metrics(outcome)          # never lost, whatever happens below
        return report_from_bag(self.bag_path, self.run_dir, plots=plots)
