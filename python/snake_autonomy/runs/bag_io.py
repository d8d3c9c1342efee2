"""Reading a run's bag back into the plain arrays of :mod:`.results` (needs rosbag, not a master).

A recorder killed half-way leaves a bag without its index: :func:`open_bag` reindexes a temporary
copy (the original is never modified) and reads every complete chunk from it. A bag without the run's
start event (cut before its first chunk, or not a run's bag) holds no run: :func:`report_from_bag`
refuses it (RunBagError) rather than report "0/0 waypoints".
"""
import json
import math
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Dict, Optional

import numpy as np

from snake_autonomy.runs.results import write_results

RUN_TOPIC = "/snake_autonomy/run"   # std_msgs/String, JSON events: start (mission, waypoints), scout, end (outcome)
INTERRUPTED = "interrupted"          # outcome of a run whose bag has no end event


class RunBagError(ValueError):
    """A bag that holds no run to report."""


def _basename(topic: str) -> str:
    return topic.rstrip("/").rsplit("/", 1)[-1]


def _is_ground_truth(topic: str) -> bool:
    """The simulator's ground_truth/* topics share the estimates' last names (com_pose, base_pose)."""
    return "ground_truth" in topic.strip("/").split("/")


@contextmanager
def open_bag(path):
    """Yields (rosbag.Bag opened for reading, reindexed: bool)."""
    import rosbag  # lazy: ROS only on this path; the module is imported without ROS too
    path = Path(path)
    try:
        bag = rosbag.Bag(str(path), "r")
    except rosbag.ROSBagUnindexedException:
        bag = None
    if bag is not None:
        try:
            yield bag, False
        finally:
            bag.close()
        return
    with tempfile.TemporaryDirectory(prefix="snake_reindex_") as tmp:
        copy = Path(tmp) / path.name
        shutil.copyfile(path, copy)
        fix = rosbag.Bag(str(copy), "a", allow_unindexed=True)
        try:
            for _ in fix.reindex():
                pass
        finally:
            fix.close()
        bag = rosbag.Bag(str(copy), "r")
        try:
            yield bag, True
        finally:
            bag.close()


def start_event(path) -> Optional[Dict[str, Any]]:
    """The run's start event (a mission's, or a navigation run's with "kind"), None when the bag has none."""
    with open_bag(path) as (bag, _):
        for _, msg, _ in bag.read_messages(topics=[RUN_TOPIC]):
            event = json.loads(msg.data)
            if event.get("event") == "start":
                return event
    return None


def _yaw(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def read_run(path, com_topic: str = "com_pose", status_topic: str = "tracking_status") -> Dict[str, Any]:
    """{waypoints, trajectory, decisions, meta, reindexed, started, messages} of a run bag (started:
    the run's start event is in it; messages: how many were read). Topics are matched by their
    last name component, so a namespaced run (/cobra/com_pose) reads the same; the simulator's
    ground_truth/com_pose is not the robot's estimate and is left out (it was interleaved once)."""
    traj = {"t": [], "x": [], "y": [], "yaw": []}
    keys = ("t", "waypoint_index", "target_index", "reached", "distance", "yaw_error_abs", "yaw_error_rel",
            "yaw_error", "w", "mode", "delta", "gait", "pose_stale", "done")
    dec = {k: [] for k in keys}
    meta: Dict[str, Any] = {}
    waypoints = []
    started, messages = False, 0
    with open_bag(path) as (bag, reindexed):
        for topic, msg, t in bag.read_messages():
            messages += 1
            name = _basename(topic)
            if topic == RUN_TOPIC:
                event = json.loads(msg.data)
                if event.get("event") == "start":
                    started = True
                    meta.update({k: v for k, v in event.items() if k != "event"})
                    waypoints = [tuple(w) for w in event.get("waypoints", [])]
                elif event.get("event") == "scout":   # a finished scout stop (missions/scout.py)
                    meta.setdefault("scouts", []).append({k: v for k, v in event.items() if k != "event"})
                elif event.get("event") == "end":
                    meta["outcome"] = event.get("outcome")
                    meta["t_end"] = event.get("t")
            elif name == com_topic and not _is_ground_truth(topic):
                stamp = msg.header.stamp.to_sec() or t.to_sec()
                traj["t"].append(stamp)
                traj["x"].append(msg.pose.position.x)
                traj["y"].append(msg.pose.position.y)
                traj["yaw"].append(_yaw(msg.pose.orientation))
            elif name == status_topic:
                dec["t"].append(msg.header.stamp.to_sec() or t.to_sec())
                dec["waypoint_index"].append(msg.waypoint_index)
                reached = bool(getattr(msg, "waypoint_reached", False))
                dec["reached"].append(reached)
                dec["target_index"].append(msg.waypoint_index - int(reached))
                for k in ("distance", "yaw_error_abs", "yaw_error_rel", "yaw_error", "w", "delta"):
                    dec[k].append(getattr(msg, k))
                dec["mode"].append(msg.mode)
                dec["gait"].append(msg.gait)
                dec["pose_stale"].append(msg.pose_stale)
                dec["done"].append(msg.done)
    order = np.argsort(np.asarray(traj["t"]), kind="stable")
    trajectory = {k: np.asarray(v, dtype=float)[order] for k, v in traj.items()}
    decisions = {k: np.asarray(v) for k, v in dec.items()}
    if "outcome" not in meta:
        # no end event: the recording process died (SIGKILL, power) before the run's final decision
        meta["outcome"] = INTERRUPTED
        meta["outcome_note"] = ("the bag has no end of run: the process recording it stopped before the "
                                "run's final decision" + (" (the bag had no index: reindexed)" if reindexed else ""))
    return {"waypoints": waypoints, "trajectory": trajectory, "decisions": decisions, "meta": meta,
            "reindexed": reindexed, "started": started, "messages": messages}


def report_from_bag(bag_path, out_dir, plots: bool = True):
    """Rebuilds the results folder of a run from its bag; returns write_results' paths. RunBagError
    (nothing written) when the bag holds no run's start event."""
    run = read_run(bag_path)
    if not run["started"]:
        raise RunBagError(f"no run in it: no start event on {RUN_TOPIC} among {run['messages']} message(s)"
                          + (" (it had no index: reindexed)" if run["reindexed"] else "")
                          + ": a truncated bag, or not a run's bag")
    meta = dict(run["meta"])
    meta["bag"] = str(bag_path)
    meta["bag_reindexed"] = run["reindexed"]
    tracker = meta.get("tracker", {})
    kwargs = {k: tracker[k] for k in ("d_th", "psi_wp", "psi_turn") if k in tracker}
    return write_results(out_dir, run["waypoints"], run["trajectory"], run["decisions"],
                         outcome=meta.get("outcome", "unknown"), meta=meta, plots=plots, **kwargs)
