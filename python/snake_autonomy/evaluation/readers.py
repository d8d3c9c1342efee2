"""Readers: TUM files, EuRoC ground-truth CSV and ROS 1 bag topics into evo trajectories.

Parsing is evo's (``evo.tools.file_interface``, bags through ``rosbags``), so what we read is exactly
what ``evo_ape`` reads. On top of it this module refuses rows that are not poses (row_checks.py: NaN,
inf, 1e308, non-unit quaternions, decreasing or repeated stamps), removes the tracking-loss markers
(null poses and, for ``nav_msgs/Odometry``, poses whose covariance says tracking is lost) and reports
both kinds of marker as tracking-loss intervals. Bag topics may be PoseStamped, PoseWithCovarianceStamped, Odometry,
TransformStamped, or a TF frame: ``/tf:PARENT.CHILD`` (evo's syntax) or ``/tf:CHILD`` (the parent is
then the root of CHILD's TF tree in the bag).
"""
import logging
import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

from .errors import EvaluationError
from .row_checks import check_rows
from .tracking_loss import LossInterval, intervals_from_mask, null_pose_mask

FORMATS = ("tum", "euroc", "bag")
# RTAB-Map publishes this covariance on every diagonal entry when odometry is lost.
LOST_COVARIANCE = 9999.0

logger = logging.getLogger(__name__)


@dataclass
class LoadedTrajectory:
    """An evo PoseTrajectory3D of trusted poses, plus where tracking was lost while reading it."""
    traj: object  # evo.core.trajectory.PoseTrajectory3D
    name: str
    loss_intervals: List[LossInterval] = field(default_factory=list)
    dropped_poses: int = 0
    warnings: List[str] = field(default_factory=list)   # accepted oddities (repeated stamps)


def guess_format(path: str) -> str:
    """'bag' for *.bag, 'euroc' for *.csv, else 'tum'."""
    lower = str(path).lower()
    if lower.endswith(".bag"):
        return "bag"
    if lower.endswith(".csv"):
        return "euroc"
    return "tum"


def load_trajectory(path: str, fmt: Optional[str] = None, topic: Optional[str] = None,
                    lost_covariance: float = LOST_COVARIANCE) -> LoadedTrajectory:
    """Reads one trajectory; raises EvaluationError with a user-facing message on any problem."""
    fmt = fmt or guess_format(path)
    if fmt not in FORMATS:
        raise EvaluationError(f"unknown format {fmt!r}: use one of {', '.join(FORMATS)}")
    if not os.path.isfile(path):
        raise EvaluationError(f"cannot read {path}: no such file")
    if fmt == "bag":
        if not topic:
            raise EvaluationError(f"{path} is a bag: name the topic (--ref-topic/--est-topic). "
                                  f"Topics in it: {describe_topics(path)}")
        traj, cov_lost = _read_bag_topic(path, topic, lost_covariance)
        name = f"{os.path.basename(path)}:{traj.name}"
    else:
        from evo.tools import file_interface  # lazy: evo is heavy and only this path needs it
        reader = (file_interface.read_euroc_csv_trajectory if fmt == "euroc"
                  else file_interface.read_tum_trajectory_file)
        try:
            traj = reader(path)
        except Exception as exc:  # evo raises FileInterfaceException, numpy ValueError, UnicodeError...
            raise EvaluationError(f"cannot read {path} as a {fmt.upper()} trajectory: {exc}") from None
        cov_lost = np.zeros(traj.num_poses, dtype=bool)
        name = os.path.basename(path)
    if traj.num_poses == 0:
        raise EvaluationError(f"{path}: no poses in it")
    warnings = check_rows(path if fmt != "bag" else name, traj.timestamps, traj.positions_xyz,
                          traj.orientations_quat_wxyz)
    loaded = _drop_lost(traj, name, cov_lost)
    loaded.warnings = warnings
    return loaded


def trajectory_from_arrays(stamps_s, xyz, quat_xyzw, name: str = "trajectory",
                           lost=None) -> LoadedTrajectory:
    """An input from arrays: stamps (n), positions (n x 3, m), quaternions (n x 4, ROS order x y z w).

    ``lost`` (n booleans, optional) marks poses known to be tracking losses; null poses are found
    anyway. Stamps must increase.
    """
    from evo.core.trajectory import PoseTrajectory3D  # lazy: evo is heavy and only this path needs it

    stamps = np.asarray(stamps_s, dtype=float).reshape(-1)
    xyz = np.asarray(xyz, dtype=float)
    quat = np.asarray(quat_xyzw, dtype=float)
    n = len(stamps)
    if xyz.shape != (n, 3) or quat.shape != (n, 4):
        raise EvaluationError(f"{name}: need n stamps, n x 3 positions and n x 4 quaternions; got "
                              f"{stamps.shape}, {xyz.shape}, {quat.shape}")
    if n == 0:
        raise EvaluationError(f"{name}: no poses")
    warnings = check_rows(name, stamps, xyz, quat)
    traj = PoseTrajectory3D(xyz, np.roll(quat, 1, axis=1), stamps, name=name)
    lost = np.zeros(n, dtype=bool) if lost is None else np.asarray(lost, dtype=bool).reshape(-1)
    if lost.shape != (n,):
        raise EvaluationError(f"{name}: 'lost' needs {n} entries, got {lost.shape}")
    loaded = _drop_lost(traj, name, lost, kind="flagged")
    loaded.warnings = warnings
    return loaded


def _drop_lost(traj, name: str, cov_lost: np.ndarray, kind: str = "covariance") -> LoadedTrajectory:
    """Removes null poses and flagged ones (cov_lost) from traj; their runs become loss intervals."""
    null = null_pose_mask(traj.positions_xyz, traj.orientations_quat_wxyz)
    lost = null | cov_lost
    stamps = np.array(traj.timestamps, dtype=float)
    intervals = (intervals_from_mask(stamps, null & ~cov_lost, "null")
                 + intervals_from_mask(stamps, cov_lost, kind))
    if lost.all():
        raise EvaluationError(f"{name}: every one of its {len(lost)} poses is a tracking loss "
                              "(null pose or lost covariance)")
    if lost.any():
        traj.reduce_to_ids(np.nonzero(~lost)[0])
    traj.name = name
    return LoadedTrajectory(traj, name, sorted(intervals, key=lambda iv: iv.start_s), int(lost.sum()))


# ---------------------------------------------------------------------------------------------- bags
def _open_bag(path: str):
    from rosbags.rosbag1 import Reader  # lazy: rosbags is heavy and only this path needs it
    reader = Reader(path)
    try:
        reader.open()
    except Exception as exc:
        raise EvaluationError(f"cannot read {path} as a ROS 1 bag: {exc}") from None
    return reader


def bag_topics(path: str) -> Dict[str, str]:
    """{topic: message type} of every topic with messages in a ROS 1 bag."""
    reader = _open_bag(path)
    try:
        return {c.topic: c.msgtype.replace("/msg/", "/")
                for c in reader.connections if c.msgcount > 0}
    finally:
        reader.close()


def describe_topics(path: str) -> str:
    topics = bag_topics(path)
    if not topics:
        return "(none)"
    return ", ".join(f"{t} [{m}]" for t, m in sorted(topics.items()))


def _resolve_topic(reader, topic: str) -> Optional[str]:
    """The topic as stored, accepting it with or without a leading slash."""
    names = set(reader.topics)
    for candidate in (topic, "/" + topic.lstrip("/"), topic.lstrip("/")):
        if candidate in names:
            return candidate
    return None


def _read_bag_topic(path: str, topic: str, lost_covariance: float):
    from evo.tools import file_interface  # lazy: evo is heavy and only this path needs it
    reader = _open_bag(path)
    try:
        if topic.split(":", 1)[0].lstrip("/") in ("tf",) and ":" in topic:
            identifier = _tf_identifier(reader, path, topic)
            try:
                traj = file_interface.read_bag_trajectory(reader, identifier)
            except Exception as exc:
                raise EvaluationError(f"{path}: cannot read TF trajectory {identifier}: {exc}") from None
            traj.name = identifier
            return traj, np.zeros(traj.num_poses, dtype=bool)
        stored = _resolve_topic(reader, topic)
        if stored is None:
            raise EvaluationError(f"{path}: no topic {topic!r}. Topics in it: {describe_topics(path)}")
        msgtype = reader.topics[stored].msgtype
        if msgtype not in file_interface.SUPPORTED_ROS_MSGS:
            raise EvaluationError(
                f"{path}: topic {stored!r} is {msgtype.replace('/msg/', '/')}, not a pose. Use a "
                "PoseStamped, PoseWithCovarianceStamped, Odometry or TransformStamped topic, or "
                f"/tf:PARENT.CHILD. Topics in it: {describe_topics(path)}")
        try:
            traj = file_interface.read_bag_trajectory(reader, stored)
        except Exception as exc:
            raise EvaluationError(f"{path}: cannot read topic {stored!r}: {exc}") from None
        cov_lost = np.zeros(traj.num_poses, dtype=bool)
        if msgtype in ("nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseWithCovarianceStamped"):
            cov_lost = _covariance_lost(reader, stored, lost_covariance)
        return traj, cov_lost
    finally:
        reader.close()


def _covariance_lost(reader, topic: str, lost_covariance: float) -> np.ndarray:
    """Per message, in bag order (evo's order): does the pose covariance diagonal reach the threshold."""
    connections = [c for c in reader.connections if c.topic == topic]
    typestore = typestore_for(connections)
    flags = []
    for connection, _, raw in reader.messages(connections=connections):
        msg = typestore.deserialize_ros1(raw, connection.msgtype)
        pose = msg.pose  # Odometry.pose and PoseWithCovarianceStamped.pose are PoseWithCovariance
        diag = np.asarray(pose.covariance, dtype=float)[[0, 7, 14, 21, 28, 35]]
        flags.append(bool(np.any(diag >= lost_covariance)))
    return np.array(flags, dtype=bool)


def _tf_identifier(reader, path: str, topic: str) -> str:
    """evo's '/tf:PARENT.CHILD' from '/tf:PARENT.CHILD' or '/tf:CHILD' (parent = root of CHILD's tree)."""
    tf_topic, _, frames = topic.partition(":")
    if "." in frames:
        return topic
    child = frames
    parents = _tf_parents(reader, tf_topic)
    if child not in parents:
        known = sorted(set(parents) | set(parents.values()))
        raise EvaluationError(f"{path}: no TF frame {child!r} on {tf_topic} (or /tf_static). "
                              f"Frames in it: {', '.join(known) if known else '(none)'}")
    root, seen = child, {child}
    while root in parents and parents[root] not in seen:
        root = parents[root]
        seen.add(root)
    return f"{tf_topic}:{root}.{child}"


def typestore_for(connections):
    """rosbags' ROS 1 typestore plus the message types these connections define in the bag
    (tf2_msgs/TFMessage and snake_autonomy/TrackingStatus are not in rosbags' own store)."""
    # lazy: rosbags is heavy and only this path needs it
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    typestore = get_typestore(Stores.ROS1_NOETIC)
    for c in connections:
        if c.msgtype not in typestore.fielddefs:
            typestore.register(get_types_from_msg(c.msgdef.data, c.msgtype))
    return typestore


def _tf_parents(reader, tf_topic: str) -> Dict[str, str]:
    topics = {tf_topic, "/" + tf_topic.lstrip("/"), "/tf_static"}
    connections = [c for c in reader.connections if c.topic in topics]
    typestore = typestore_for(connections)
    parents: Dict[str, str] = {}
    for connection, _, raw in reader.messages(connections=connections):
        msg = typestore.deserialize_ros1(raw, connection.msgtype)
        for tf in msg.transforms:
            parents.setdefault(tf.child_frame_id.lstrip("/"), tf.header.frame_id.lstrip("/"))
    return parents
