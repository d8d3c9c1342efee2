"""The calibration on the robot through ROS: gait commands to driver_node, com_pose back from it.

    robot = connect(command_topic="gait_command", pose_topic="com_pose")   # after rospy.init_node
    outcome = run_plan(robot, plan)             # sequence.run_plan: the same sequence as in simulation

The base pose is whatever feeds the driver's base_pose (motion capture, or the pose remapper from
RTAB-Map); the driver turns it into com_pose (centre of mass + virtual chassis orientation), which
is what the tracker uses and what the calibration measures. The driver publishes com_pose only from
a fresh base pose, so a silent com_pose is a stale pose: run_plan then holds the robot.

RosRobot itself is ROS-free (a publish function in, poses pushed by on_pose), so its sequencing is
tested without a master; connect() does the rospy wiring. Time is the poses' header stamps.
"""
import queue
import time
from typing import Callable, Optional, Tuple

from ..transforms import yaw_of_quat

Pose = Tuple[float, float, float, float]


class RosRobot:
    def __init__(self, publish: Callable[[str, bool, float], None]):
        """publish(gait, steer, delta_rad): sends one GaitCommand."""
        self._publish = publish
        self._poses: "queue.Queue[Pose]" = queue.Queue()
        self.commands = 0

    def on_pose(self, t_s: float, x_m: float, y_m: float, yaw_rad: float) -> None:
        """A com_pose arrived (any thread)."""
        self._poses.put((float(t_s), float(x_m), float(y_m), float(yaw_rad)))

    def command(self, gait: str, steer: bool, delta_rad: float) -> str:
        self._publish(gait, bool(steer), float(delta_rad))
        self.commands += 1
        return ""       # the driver's refusals are on /diagnostics, not on the topic

    def next_pose(self, timeout_s: float) -> Optional[Pose]:
        """The next com_pose, waiting at most timeout_s of wall time (None: stale)."""
        try:
            return self._poses.get(timeout=timeout_s)
        except queue.Empty:
            return None


def connect(command_topic: str = "gait_command", pose_topic: str = "com_pose",
            subscriber_timeout_s: float = 5.0) -> RosRobot:
    """The rospy wiring (rospy.init_node first); RuntimeError when no driver listens."""
    import rospy  # lazy: ROS only on this path; the module is imported without ROS too
    from geometry_msgs.msg import PoseStamped

    from snake_autonomy.msg import GaitCommand

    pub = rospy.Publisher(command_topic, GaitCommand, queue_size=10)

    def publish(gait, steer, delta_rad):
        msg = GaitCommand(gait=gait, steer=steer, delta=delta_rad)
        msg.header.stamp = rospy.Time.now()
        pub.publish(msg)

    robot = RosRobot(publish)

    def on_msg(msg):
        o, p = msg.pose.orientation, msg.pose.position
        t = msg.header.stamp.to_sec() or rospy.get_time()
        robot.on_pose(t, p.x, p.y, yaw_of_quat(o.x, o.y, o.z, o.w))

    rospy.Subscriber(pose_topic, PoseStamped, on_msg, queue_size=200)
    deadline = time.monotonic() + subscriber_timeout_s
    while pub.get_num_connections() == 0:
        if time.monotonic() > deadline or rospy.is_shutdown():
            raise RuntimeError(f"nobody subscribes to {rospy.resolve_name(command_topic)} after "
                               f"{subscriber_timeout_s:g} s: is driver_node running?")
        time.sleep(0.05)
    return robot
