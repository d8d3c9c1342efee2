"""Scout trajectories on the ROS side: the message and the executor that publishes it.

`to_msg` turns planning/fbsr/trajectory.py's points into a trajectory_msgs/JointTrajectory (joint_1 ..
joint_N, radians, time_from_start; header.stamp zero: start on receipt). `TopicTrajectoryExecutor`
is missions/scout.py's TrajectoryExecutor for the mission node: it publishes on
`driver/joint_trajectory` (the driver's TrajectorySource) with a header.frame_id of its own
(the driver's id for it) and counts it finished when `driver/trajectory_status` says so for that id:
done (the last point held), aborted or refused (`aborted` keeps why). The head's height while a raise is
held is base_pose's z (base_link is the head module; the robot's pose source: motion capture or the
remapped odometry). Pure wiring: no node, no master needed to build a message.
"""
import math
import threading

import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from snake_autonomy.msg import TrajectoryStatus

TOPIC = "driver/joint_trajectory"
STATUS_TOPIC = "driver/trajectory_status"
POSE_TOPIC = "base_pose"            # base_link's pose: its z is the head's height
ENDED = ("done", "aborted", "refused")


def to_msg(trajectory, frame_id: str = "") -> JointTrajectory:
    msg = JointTrajectory()
    msg.header.frame_id = frame_id
    msg.joint_names = list(trajectory.joint_names)
    for p in trajectory.points:
        point = JointTrajectoryPoint()
        point.positions = list(p.positions_rad)
        point.velocities = list(p.velocities_rad_s)
        point.time_from_start = rospy.Duration.from_sec(p.time_from_start_s)
        msg.points.append(point)
    return msg


class TopicTrajectoryExecutor:
    """Publishes scout trajectories to the driver and follows them on driver/trajectory_status. The
    driver refuses a bad trajectory whole (every reason on the status and its diagnostics); the
    planner's checks (missions/scout.py) make that the exception, so `execute` accepts once published
    and a refusal shows as finished with `aborted` set."""

    def __init__(self, publisher=None, subscribe: bool = True):
        self.pub = publisher if publisher is not None else rospy.Publisher(
            TOPIC, JointTrajectory, queue_size=1, latch=False)
        self._lock = threading.Lock()
        self._ended = {}                    # trajectory id -> its final TrajectoryStatus
        self._id, self._count = None, 0
        self.aborted = ""
        self._head_z = math.nan
        if subscribe:
            self.sub = rospy.Subscriber(STATUS_TOPIC, TrajectoryStatus, self.on_status)
            self.pose_sub = rospy.Subscriber(POSE_TOPIC, PoseWithCovarianceStamped, self.on_pose, queue_size=1)

    def on_pose(self, msg) -> None:
        self._head_z = msg.pose.pose.position.z

    def head_height_m(self) -> float:
        return self._head_z

    def on_status(self, msg) -> None:
        if msg.phase in ENDED:
            with self._lock:
                self._ended[msg.id] = msg

    def execute(self, trajectory, t_s: float) -> str:
        if self.pub.get_num_connections() == 0:
            return f"nobody subscribes to {self.pub.resolved_name} (is the driver running?)"
        self._count += 1
        self._id = f"scout {self._count} {t_s:.2f}"
        self.aborted = ""
        self.pub.publish(to_msg(trajectory, frame_id=self._id))
        return ""

    def finished(self, t_s: float) -> bool:
        with self._lock:
            end = self._ended.get(self._id)
        if end is None:
            return self._id is None
        if end.phase != "done":
            self.aborted = f"{end.phase} {end.abort}: {end.reason}".strip()
        return True
