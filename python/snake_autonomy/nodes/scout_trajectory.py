"""Scout trajectories on the ROS side: the message and the executor that publishes it.

`to_msg` turns planning/fbsr/trajectory.py's points into a trajectory_msgs/JointTrajectory (joint_1 ..
joint_N, radians, time_from_start; header.stamp zero: start on receipt). `TopicTrajectoryExecutor`
is missions/scout.py's TrajectoryExecutor for the mission node: it publishes on
`driver/joint_trajectory` (the driver's TrajectorySource, issue 11) and counts a trajectory finished
once its duration (plus a settle margin) has passed. Pure wiring: no node, no master needed to build
a message.
"""
import rospy
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

TOPIC = "driver/joint_trajectory"
SETTLE_MARGIN_S = 0.5


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
    """Publishes scout trajectories to the driver. The driver refuses a bad trajectory whole and
    says why on its own diagnostics; the planner's checks (missions/scout.py) make that the
    exception, so this executor accepts once published and times the motion."""

    def __init__(self, publisher=None, settle_margin_s: float = SETTLE_MARGIN_S):
        self.pub = publisher if publisher is not None else rospy.Publisher(
            TOPIC, JointTrajectory, queue_size=1, latch=False)
        self.settle_margin_s = float(settle_margin_s)
        self._end_s = float("-inf")

    def execute(self, trajectory, t_s: float) -> str:
        if self.pub.get_num_connections() == 0:
            return f"nobody subscribes to {self.pub.resolved_name} (is the driver running?)"
        self.pub.publish(to_msg(trajectory))
        self._end_s = t_s + trajectory.duration_s + self.settle_margin_s
        return ""

    def finished(self, t_s: float) -> bool:
        return t_s >= self._end_s
