"""planner_node's goals the ROS way (move_base's conventions): rviz's "2D Nav Goal", a move_base action
server, the goal shown in rviz. Wiring only: the loop's goal is NavLoop.set_goal / clear_goal, which
planner_node calls with what GoalServer.poll() returns.

Subscribes  move_base_simple/goal (geometry_msgs/PoseStamped: rviz's "2D Nav Goal"): the new goal, radius
            ~goal_radius_m; it preempts an active action goal.
Actions     move_base (move_base_msgs/MoveBaseAction): goal -> the planner's goal (radius ~goal_radius_m);
            feedback every tick (base_position: base_link's latest pose); SUCCEEDED once base_link is inside
            the goal's disc; ABORTED with the reason when the goal cannot be used, or after ~abort_after_s
            without following (no free arc, a stale input, a failing tick, no camera yet: the robot holds);
            PREEMPTED by a new goal (action or topic: the new one takes over) or by a cancel (the goal is
            cleared: the robot holds, keeping its posture).
Publishes   nav/goal (visualization_msgs/Marker, latched): the goal's disc in the world frame, deleted
            when there is none.
Frames      a goal's position (its orientation is not used: the planner drives into a disc) is transformed
            into the planner's world frame with tf2 (the latest transform); the robot holds while it is
            looked up (TF_WAIT_S at most). The tf2 listener is made at the first goal in another frame,
            not at start: a Python listener decodes every /tf message (the driver's and the robot
            state publisher's, 100 Hz) in the planner's process, CPU a goal in the world frame never needs.
Refusals    every new goal takes over at once (the goal it replaces ends: an action goal PREEMPTED). One
            it cannot use (no frame_id, no transform, a position not finite) is refused with a warning
            naming the frames, an action goal ABORTED with that text, and the robot holds (as move_base
            stops on a goal it cannot transform).

The action server is polled from the planner's tick (no callbacks): the goal changes in one thread only,
and an action goal is SUCCEEDED or ABORTED for the loop state it produced.
"""
import threading
from dataclasses import dataclass
from typing import Callable, Optional, Tuple

import actionlib
import numpy as np
import rospy
import tf2_ros
from geometry_msgs.msg import PoseStamped
from move_base_msgs.msg import MoveBaseAction, MoveBaseFeedback
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker

from snake_autonomy.planning.rectilinear.nav_loop import FOLLOWING, GOAL_REACHED
from snake_autonomy.transforms import quat_to_matrix

PARAMETER, TOPIC, ACTION = "parameter", "move_base_simple/goal", "move_base action"
TF_WAIT_S = 1.0          # a goal's transform not known this long after the goal came: refused
GOAL_COLOUR = ColorRGBA(0.2, 0.6, 1.0, 0.5)


@dataclass(frozen=True)
class Goal:
    xy: Tuple[float, float]            # in the planner's world frame
    radius_m: float
    source: str                        # PARAMETER | TOPIC | ACTION


class GoalServer:
    def __init__(self, goal: Optional[Goal], radius_m: float, abort_after_s: float, world_frame: Callable[[], str]):
        """goal: the one given at start (~world or ~goal), or None; radius_m: of the goals that arrive;
        world_frame(): the planner's world frame ("" while unknown)."""
        self.radius_m, self.abort_after_s, self.world_frame = radius_m, abort_after_s, world_frame
        self.goal, self.seq = goal, 0      # seq: counts the goal changes (the node applies each once)
        self.refused = 0
        self.last_refusal = ""
        self.last_outcome = ""             # how the last action goal ended
        self._simple = None                # the latest move_base_simple/goal, taken at the next poll
        self._trouble = None               # since when the action goal's loop has not been following (s)
        self._shown = None                 # the seq nav/goal shows
        self._stopped = False
        self.lock = threading.Lock()       # before the action server's locks, never after
        self._unresolved = None            # (PoseStamped, source, deadline_s): the new goal, its transform awaited
        self.tf = self.tf_listener = None  # made at the first goal in another frame than the world's
        self.pub_goal = rospy.Publisher("nav/goal", Marker, queue_size=1, latch=True)
        rospy.Subscriber("move_base_simple/goal", PoseStamped, self.on_simple_goal, queue_size=1)
        self.action = actionlib.SimpleActionServer("move_base", MoveBaseAction, auto_start=False)
        self.action.start()
        rospy.core.add_preshutdown_hook(lambda reason: self.end_action(f"planner shutting down: {reason}"))
        rospy.on_shutdown(self.stop)

    def on_simple_goal(self, msg):
        self._simple = msg                 # one assignment: the tick's poll takes it

    # -- the tick's side -------------------------------------------------------------------------
    def poll(self) -> Tuple[Optional[Goal], int]:
        """Takes what arrived since the last tick (an action goal, a cancel, a topic goal, in that order)
        and returns the goal now (None: hold) with its seq."""
        with self.lock:
            if self._stopped:
                return self.goal, self.seq
            now_s = rospy.get_time()
            if self.action.is_new_goal_available():          # the active one (if any) ends PREEMPTED
                self._unresolved = (self.action.accept_new_goal().target_pose, ACTION, now_s + TF_WAIT_S)
            elif self.action.is_active() and self.action.is_preempt_requested():
                self.action.set_preempted(text="canceled: holding")
                self._unresolved = None
                self.set_goal(None, "action goal canceled: holding")
            simple, self._simple = self._simple, None
            if simple is not None:
                if self.action.is_active():
                    self.last_outcome = f"preempted by a goal on {TOPIC}"
                    self.action.set_preempted(text=self.last_outcome)
                self._unresolved = (simple, TOPIC, now_s + TF_WAIT_S)
            if self._unresolved is not None:
                self.resolve(now_s)
            self.show()
            return self.goal, self.seq

    def report(self, now_s: float, state: str, message: str, base_pose: Optional[PoseStamped]) -> None:
        """After the tick: feedback, and the action goal's end (succeeded, aborted) when it has come."""
        with self.lock:
            if self._stopped or not self.action.is_active():
                return
            if base_pose is not None:
                self.action.publish_feedback(MoveBaseFeedback(base_position=base_pose))
            if state == GOAL_REACHED:
                self.last_outcome = f"succeeded: {message}"
                self.action.set_succeeded(text=message)
                rospy.loginfo(f"planner: action goal succeeded ({message})")
            elif state == FOLLOWING:
                self._trouble = None
            elif self._trouble is None:
                self._trouble = now_s
            elif now_s - self._trouble >= self.abort_after_s:
                why = (f"not following for {now_s - self._trouble:.0f} s (~abort_after_s {self.abort_after_s:g}), "
                       f"now {state}: {message}")
                self.last_outcome = f"aborted: {why}"
                self.action.set_aborted(text=why)
                self.set_goal(None, f"action goal aborted: {why}")

    # -- goals -------------------------------------------------------------------------------------
    def resolve(self, now_s: float) -> None:
        """The new goal in the world frame: taken; its transform not there yet: hold and try again at the
        next tick until TF_WAIT_S after it came; else refused (an action goal ABORTED) and hold."""
        msg, source, deadline_s = self._unresolved
        xy, why, retry = self.to_world(msg)
        if xy is not None:
            self._unresolved = None
            self.set_goal(Goal(xy, self.radius_m, source), f"goal from {source}")
        elif retry and now_s < deadline_s:
            if self.goal is not None:
                self.set_goal(None, f"goal from {source}: holding while looking up its transform ({why})")
        else:
            self._unresolved = None
            self.refuse(why)
            if source == ACTION and self.action.is_active():
                self.last_outcome = f"aborted: {why}"
                self.action.set_aborted(text=why)
            if self.goal is not None:
                self.set_goal(None, "the goal refused replaced the current one: holding")

    def set_goal(self, goal: Optional[Goal], what: str) -> None:
        self.goal, self.seq, self._trouble = goal, self.seq + 1, None
        if goal is None:
            rospy.loginfo(f"planner: {what}")
        else:
            rospy.loginfo(f"planner: {what} ({goal.xy[0]:.3f}, {goal.xy[1]:.3f}) in {self.world_frame()!r}, "
                          f"radius {goal.radius_m:g} m")

    def refuse(self, why: str) -> None:
        self.refused += 1
        self.last_refusal = why
        rospy.logwarn(f"planner: goal refused: {why}")

    def to_world(self, msg) -> Tuple[Optional[Tuple[float, float]], Optional[str], bool]:
        """(x, y) of a PoseStamped's position in the world frame, or (None, why not, whether a later
        try may succeed: the transform is not known yet)."""
        frame, world = msg.header.frame_id, self.world_frame()
        p = msg.pose.position
        xyz = np.array([p.x, p.y, p.z], float)
        if not np.all(np.isfinite(xyz)):
            return None, f"position {tuple(xyz)} not finite", False
        if not world:
            return None, "the planner's world frame is not known yet (no base_pose so far; ~world_frame sets it)", False
        if not frame:
            return None, f"no frame_id: give header.frame_id (the planner's world frame is {world!r})", False
        if frame != world:
            if self.tf is None:                # the first goal in another frame: listen from now on
                self.tf = tf2_ros.Buffer()
                self.tf_listener = tf2_ros.TransformListener(self.tf)
            try:
                t = self.tf.lookup_transform(world, frame, rospy.Time(0)).transform
            except tf2_ros.TransformException as exc:
                return None, (f"goal frame {frame!r} has no transform to the planner's world frame {world!r} "
                              f"({str(exc).strip()})"), True
            r, v = t.rotation, t.translation
            xyz = quat_to_matrix(r.x, r.y, r.z, r.w) @ xyz + (v.x, v.y, v.z)
        return (float(xyz[0]), float(xyz[1])), None, False

    def show(self) -> None:
        """nav/goal: the goal's disc (latched), once per change, when the world frame is known."""
        world = self.world_frame()
        if not world or self._shown == self.seq:
            return
        m = Marker()
        m.header.stamp, m.header.frame_id = rospy.Time.now(), world
        m.ns, m.id = "nav_goal", 0
        if self.goal is None:
            m.action = Marker.DELETE
        else:
            m.type, m.action = Marker.CYLINDER, Marker.ADD
            m.pose.position.x, m.pose.position.y = self.goal.xy
            m.pose.orientation.w = 1.0
            m.scale.x = m.scale.y = 2.0 * self.goal.radius_m
            m.scale.z = 0.01
            m.color = GOAL_COLOUR
        self.pub_goal.publish(m)
        self._shown = self.seq

    # -- diagnostics and shutdown ---------------------------------------------------------------
    def diagnose(self, stat) -> None:
        g = self.goal
        stat.add("goal", "none" if g is None else f"({g.xy[0]:.3f}, {g.xy[1]:.3f}) radius {g.radius_m:g} m "
                                                 f"from {g.source}")
        stat.add("goals_refused", str(self.refused))
        stat.add("last_goal_refusal", self.last_refusal or "none")
        stat.add("last_action_outcome", self.last_outcome or "none")

    def end_action(self, why: str) -> None:
        """Aborts an active action goal (before rospy closes its publishers: a preshutdown hook)."""
        with self.lock:
            if not self._stopped and self.action.is_active():
                self.action.set_aborted(text=why)

    def stop(self) -> None:
        """Stops the action server (its status timer, topics) once: rospy.on_shutdown."""
        with self.lock:
            if not self._stopped:
                self._stopped = True
                self.action.action_server.stop()

