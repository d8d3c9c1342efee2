"""Splitting the error of a run by segment: per gait, per mission leg, per tracker mode.

The segmentation comes from the waypoint tracker's ``snake_autonomy/TrackingStatus`` messages that
the logger records in the same bag as the poses (``/tracking_status``, 1 Hz). A status holds from its
header stamp until the next status; pairs before the first status are labelled ``before start``.
``pose_stale`` statuses become tracking-loss intervals (the tracker held locomotion).

Groups by key:
- ``gait``: the commanded gait string;
- ``leg``: ``waypoint N`` while heading to waypoint N (0-based), ``done`` once the mission is over;
- ``mode``: sidewind / FAR turn / NEAR turn (turn-in-place is the thesis's pure-rotation failure mode).
"""
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence

import numpy as np

from .errors import EvaluationError
from .readers import _resolve_topic, describe_topics, typestore_for
from .stats import statistics
from .tracking_loss import LossInterval

STATUS_TOPIC = "/tracking_status"
SEGMENT_KEYS = ("gait", "leg", "mode")
MODE_NAMES = {1: "sidewind", 2: "FAR turn", 3: "NEAR turn"}
BEFORE_START = "before start"


@dataclass(frozen=True)
class StatusSample:
    """The fields of one TrackingStatus that segment a run."""
    stamp_s: float
    waypoint_index: int
    num_waypoints: int
    gait: str
    mode: int
    pose_stale: bool = False
    done: bool = False

    def label(self, key: str) -> str:
        if key == "gait":
            return self.gait or "(no gait)"
        if key == "leg":
            if self.done or (self.num_waypoints and self.waypoint_index >= self.num_waypoints):
                return "done"
            return f"waypoint {self.waypoint_index}"
        if key == "mode":
            return MODE_NAMES.get(self.mode, f"mode {self.mode}")
        raise ValueError(f"unknown segment key {key!r}: use one of {', '.join(SEGMENT_KEYS)}")


def read_tracking_status(bag_path: str, topic: str = STATUS_TOPIC) -> List[StatusSample]:
    """Every TrackingStatus on ``topic`` of a ROS 1 bag, sorted by header stamp.

    The message definition is taken from the bag itself, so this works without the package built.
    """
    from rosbags.rosbag1 import Reader  # lazy: rosbags is heavy and only this path needs it


    try:
        reader = Reader(bag_path)
        reader.open()
    except Exception as exc:
        raise EvaluationError(f"cannot read {bag_path} as a ROS 1 bag: {exc}") from None
    try:
        stored = _resolve_topic(reader, topic)
        if stored is None:
            raise EvaluationError(f"{bag_path}: no topic {topic!r} for segments. "
                                  f"Topics in it: {describe_topics(bag_path)}")
        connections = [c for c in reader.connections if c.topic == stored]
        for c in connections:
            if not c.msgtype.endswith("TrackingStatus"):
                raise EvaluationError(f"{bag_path}: topic {stored!r} is {c.msgtype}, not TrackingStatus")
        typestore = typestore_for(connections)
        samples = []
        for connection, _, raw in reader.messages(connections=connections):
            msg = typestore.deserialize_ros1(raw, connection.msgtype)
            stamp = msg.header.stamp
            samples.append(StatusSample(
                stamp.sec + stamp.nanosec * 1e-9, int(msg.waypoint_index), int(msg.num_waypoints),
                str(msg.gait), int(msg.mode), bool(msg.pose_stale), bool(msg.done)))
    finally:
        reader.close()
    return sorted(samples, key=lambda s: s.stamp_s)


def status_loss_intervals(samples: Sequence[StatusSample]) -> List[LossInterval]:
    """pose_stale runs as intervals from the first stale status to the next fresh one."""
    intervals = []
    i = 0
    while i < len(samples):
        if not samples[i].pose_stale:
            i += 1
            continue
        j = i
        while j + 1 < len(samples) and samples[j + 1].pose_stale:
            j += 1
        end = samples[j + 1].stamp_s if j + 1 < len(samples) else samples[j].stamp_s
        intervals.append(LossInterval(samples[i].stamp_s, end, "pose_stale"))
        i = j + 1
    return intervals


def labels_at(stamps: np.ndarray, samples: Sequence[StatusSample], key: str) -> List[str]:
    """The segment label of every stamp: the label of the last status at or before it."""
    status_stamps = np.array([s.stamp_s for s in samples], dtype=float)
    idx = np.searchsorted(status_stamps, np.asarray(stamps, dtype=float), side="right") - 1
    return [samples[k].label(key) if k >= 0 else BEFORE_START for k in idx]


def spans(samples: Sequence[StatusSample], key: str, end_s: Optional[float] = None):
    """[(start_s, end_s, label)] of the runs of equal label, for shading plots."""
    out = []
    for s in samples:
        label = s.label(key)
        if out and out[-1][2] == label:
            continue
        if out:
            out[-1] = (out[-1][0], s.stamp_s, out[-1][2])
        out.append((s.stamp_s, s.stamp_s, label))
    if out:
        last = end_s if end_s is not None and end_s > out[-1][0] else samples[-1].stamp_s
        out[-1] = (out[-1][0], last, out[-1][2])
    return out


def segment_statistics(errors: np.ndarray, stamps: np.ndarray, samples: Sequence[StatusSample],
                       keys: Sequence[str] = SEGMENT_KEYS) -> Dict[str, List[dict]]:
    """{key: [{label, pairs, stats}, ...]} in order of first appearance, over the given pairs."""

    errors = np.asarray(errors, dtype=float)
    out: Dict[str, List[dict]] = {}
    if not samples:
        return out
    for key in keys:
        labels = np.array(labels_at(stamps, samples, key), dtype=object)
        groups = []
        for label in dict.fromkeys(labels.tolist()):
            sel = labels == label
            groups.append({"label": label, "pairs": int(sel.sum()), "stats": statistics(errors[sel])})
        out[key] = groups
    return out
