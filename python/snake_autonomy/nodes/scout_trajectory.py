"""Scout trajectories on the ROS side: the message and the executor that publishes it.

`to_msg` turns planning/fbsr/trajectory.py's points into a trajectory_msgs/JointTrajectory (joint_1 ..
joint_N, radians, time_from_start; header.stamp zero: start on receipt). `TopicTrajectoryExecutor`
is missions/scout.py's TrajectoryExecutor for the mission node: it publishes on
`driver/joint_trajectory` (the driver's TrajectorySource) with a header.frame_id of its own
(the driver's id for it) and counts it finished when `driver/trajectory_status` says so for that id:
done (the last point held), aborted or refused (`aborted` keeps why). The head's height while a raise is
held is base_pose's z (base_link is the head module; the robot's pose source: motion capture or the
remapped odometry). Pure wiring: no node, no master needed to build a message.

A trajectory is never waited for forever (the message dropped, the driver restarted or dead): with no
status at all for its id within ``accept_timeout_s`` (~scout_accept_timeout_s, 3 s; the driver answers
running or refused at its next loop cycle), or no final status within its duration (the last point's
time_from_start) + ``result_margin_s`` (~scout_result_margin_s, 5 s) of being sent, it counts as
finished with `aborted` saying what was waited for and how long. Statuses of other ids (another
sender's trajectories, the latched status of an earlier one) and a late final status of a trajectory
given up are logged and ignored. Times are the caller's ``t_s`` (execute and finished).
"""
import math
import threading
from collections import deque

import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from snake_autonomy.missions.scout import RESULT_MARGIN_S  # ~scout_result_margin_s's default
from snake_autonomy.msg import TrajectoryStatus

TOPIC = "driver/joint_trajectory"
STATUS_TOPIC = "driver/trajectory_status"
POSE_TOPIC = "base_pose"            # base_link's pose: its z is the head's height
ENDED = ("done", "aborted", "refused")
ACCEPT_TIMEOUT_S = 3.0       # ~scout_accept_timeout_s: any status for a trajectory sent


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


class _Goal:
    """The trajectory waited for: its id, when it was sent (the caller's t_s) and its duration."""

    def __init__(self, trajectory_id: str, sent_s: float, duration_s: float):
        self.id, self.sent_s, self.duration_s = trajectory_id, sent_s, duration_s
        self.answered = False               # any status for it: the driver has it (running) or refused it
        self.final = None                   # its final TrajectoryStatus


class TopicTrajectoryExecutor:
    """Publishes scout trajectories to the driver and follows them on driver/trajectory_status. The
    driver refuses a bad trajectory whole (every reason on the status and its diagnostics); the
    planner's checks (missions/scout.py) make that the exception, so `execute` accepts once published
    and a refusal shows as finished with `aborted` set. A trajectory the driver never answers, or never
    ends, is given up after its deadlines (the module's docstring): finished, `aborted` says why."""

    def __init__(self, publisher=None, subscribe: bool = True, accept_timeout_s: float = ACCEPT_TIMEOUT_S,
                 result_margin_s: float = RESULT_MARGIN_S):
        for key, value in (("scout_accept_timeout_s", accept_timeout_s), ("scout_result_margin_s", result_margin_s)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"~{key}: must be a positive number of seconds, got {value!r}")
        self.accept_timeout_s, self.result_margin_s = float(accept_timeout_s), float(result_margin_s)
        self.pub = publisher if publisher is not None else rospy.Publisher(
            TOPIC, JointTrajectory, queue_size=1, latch=False)
        self._lock = threading.Lock()
        self._goal = None                   # the last trajectory sent (_Goal), None before the first
        # ids of trajectories given up, the goal's among them once it is given up (only the goal is ever
        # given up, so it is the newest); their late statuses are ignored
        self._given_up = deque(maxlen=16)
        self._count = 0
        self.aborted = ""
        self._head_z = math.nan
        if subscribe:
            self.sub = rospy.Subscriber(STATUS_TOPIC, TrajectoryStatus, self.on_status)
            self.pose_sub = rospy.Subscriber(POSE_TOPIC, PoseWithCovarianceStamped, self.on_pose, queue_size=1)

    @classmethod
    def from_params(cls) -> "TopicTrajectoryExecutor":
        return cls(accept_timeout_s=float(rospy.get_param("~scout_accept_timeout_s", ACCEPT_TIMEOUT_S)),
                   result_margin_s=float(rospy.get_param("~scout_result_margin_s", RESULT_MARGIN_S)))

    def on_pose(self, msg) -> None:
        self._head_z = msg.pose.pose.position.z

    def head_height_m(self) -> float:
        return self._head_z

    def on_status(self, msg) -> None:
        """A driver/trajectory_status message (rospy's thread): kept when it is the trajectory waited for."""
        trajectory_id, phase = str(msg.id), str(msg.phase)
        with self._lock:
            goal = self._goal
            given_up = trajectory_id in self._given_up
            ours = goal is not None and goal.id == trajectory_id and not given_up
            if ours:
                goal.answered = True
                if phase in ENDED and goal.final is None:
                    goal.final = msg
        if given_up and phase in ENDED:
            rospy.logwarn(f"{STATUS_TOPIC}: '{trajectory_id}' {phase} came after it was given up: ignored")
        elif not ours:
            rospy.logdebug(f"{STATUS_TOPIC}: '{trajectory_id}' {phase} is not the scout trajectory waited for: ignored")

    def execute(self, trajectory, t_s: float) -> str:
        if self.pub.get_num_connections() == 0:
            return f"nobody subscribes to {self.pub.resolved_name} (is the driver running?)"
        self._count += 1
        msg = to_msg(trajectory, frame_id=f"scout {self._count} {t_s:.2f}")
        duration_s = msg.points[-1].time_from_start.to_sec() if msg.points else 0.0
        with self._lock:
            self._goal = _Goal(msg.header.frame_id, float(t_s), duration_s)
            self.aborted = ""
        self.pub.publish(msg)
        return ""

    def finished(self, t_s: float) -> bool:
        with self._lock:
            goal = self._goal
            if goal is None:
                return True
            if goal.id in self._given_up:
                return True
            if goal.final is not None:
                end = goal.final
                if end.phase != "done":
                    self.aborted = f"{end.phase} {end.abort}: {end.reason}".strip()
                return True
            waited_s = t_s - goal.sent_s
            why = ""
            if not goal.answered and waited_s > self.accept_timeout_s:
                why = (f"no status for trajectory '{goal.id}' within {self.accept_timeout_s:.1f} s of sending it "
                       f"(the driver answers running or refused on {STATUS_TOPIC}; is it running?)")
            elif waited_s > goal.duration_s + self.result_margin_s:
                why = (f"no final status for trajectory '{goal.id}' within "
                       f"{goal.duration_s + self.result_margin_s:.1f} s ({goal.duration_s:.1f} s trajectory + "
                       f"{self.result_margin_s:.1f} s)")
            if not why:
                return False
            self._given_up.append(goal.id)
            self.aborted = why
        rospy.logerr(f"scout trajectory given up: {why}")
        return True

