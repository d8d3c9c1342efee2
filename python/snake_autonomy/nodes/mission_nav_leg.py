"""mission_node's navigate_to legs (missions/nav_leg.py) as move_base action goals: the runner's Navigator.

Action client  move_base (move_base_msgs/MoveBaseAction; planner_node serves it, move_base's conventions):
               one goal per leg, target_pose in the mission's world frame (~world_frame: the frame of the
               tracker's waypoints and poses), position (x_m, y_m), orientation heading_deg.
Settle         before the goal goes out the mission node sends its hold (repeated every second) for
               ~nav_settle_s (4 s): the tracker's gait (sidewinding, a turn) decays to a straight body at
               rest, and the planner's first replan sees a camera frame taken from there. From the goal on
               the mission node sends nothing: planner_node commands until the goal ends (its last command
               the stop gait keeping the body's curvature). The leg reached (the goal SUCCEEDED or the
               centre of mass inside radius_m), the runner's after-hold (MissionRunner leg_hold_s, this
               navigator's settle_s) sends the hold every tick for ~nav_settle_s, straightening the body,
               and the tracker's gait follows at the next tick. Without either settle the simulated COBRA
               rolled over: onto its side when the rectilinear gait took over mid-sidewind, onto its back
               when sidewinding started from the curved rectilinear stop.
Params         ~nav_server_timeout_s (10: a leg's wait for the move_base server), ~nav_settle_s (4; 0: none).
Outcomes       SUCCEEDED: the leg is reached. ABORTED, PREEMPTED (by another goal on the planner),
               REJECTED, RECALLED, LOST: the leg failed, with the server's text; the runner aborts the
               mission naming the leg. No server within ~nav_server_timeout_s: failed, naming the action.
Cancel         the mission aborted, paused, timed out or ended: the goal is cancelled (the planner holds).

The client is made at the first leg, so a mission without legs never connects; the server is awaited in
a worker thread (the 1 Hz tick polls, never blocks). Goal callbacks arrive in rospy's threads; a
generation number drops those of a goal cancelled or replaced since.
"""
import math
import threading
import time
from typing import Callable, Optional, Tuple

import actionlib
import rospy
from actionlib_msgs.msg import GoalStatus
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal

from snake_autonomy.missions.nav_leg import ACTIVE, FAILED, PENDING, SUCCEEDED, NavLegSpec

#: How a move_base goal's end reads for the runner: GoalStatus -> (navigator state, word).
ENDS = {GoalStatus.SUCCEEDED: (SUCCEEDED, "succeeded"), GoalStatus.ABORTED: (FAILED, "aborted"),
        GoalStatus.PREEMPTED: (FAILED, "preempted"), GoalStatus.REJECTED: (FAILED, "rejected"),
        GoalStatus.RECALLED: (FAILED, "recalled"), GoalStatus.LOST: (FAILED, "lost")}


def move_base_goal(leg: NavLegSpec, frame_id: str) -> MoveBaseGoal:
    goal = MoveBaseGoal()
    goal.target_pose.header.frame_id = frame_id
    goal.target_pose.header.stamp = rospy.Time.now()
    goal.target_pose.pose.position.x, goal.target_pose.pose.position.y = leg.x_m, leg.y_m
    half = math.radians(leg.heading_deg) / 2.0
    goal.target_pose.pose.orientation.z, goal.target_pose.pose.orientation.w = math.sin(half), math.cos(half)
    return goal


class MoveBaseNavigator:
    def __init__(self, world_frame: str, server_timeout_s: float, action_name: str = "move_base",
                 settle_s: float = 0.0, hold: Optional[Callable[[str], None]] = None):
        """hold(why): sends the mission's hold gait, logged unless why is empty (the settle before a goal;
        settle_s 0: none). The runner reads settle_s for its after-hold of a reached leg."""
        if not (math.isfinite(server_timeout_s) and server_timeout_s > 0):
            raise ValueError(f"~nav_server_timeout_s: must be a positive number of seconds, got {server_timeout_s!r}")
        if not (math.isfinite(settle_s) and settle_s >= 0):
            raise ValueError(f"~nav_settle_s: must be a number of seconds >= 0, got {settle_s!r}")
        self.world_frame, self.server_timeout_s = world_frame, float(server_timeout_s)
        self.settle_s, self.hold = float(settle_s), hold
        self.action_name = rospy.resolve_name(action_name)
        self.client = None
        self.lock = threading.Lock()
        self.generation = 0            # counts sends and cancels: callbacks of an older goal are dropped
        self.goal_sent = False         # a goal of the current generation went to the server
        self.handed = 0                # the generation whose send_goal has returned
        self.state: Tuple[str, str] = (PENDING, "")

    @classmethod
    def from_params(cls, world_frame: str, hold: Callable[[str], None]) -> "MoveBaseNavigator":
        return cls(world_frame, float(rospy.get_param("~nav_server_timeout_s", 10.0)),
                   settle_s=float(rospy.get_param("~nav_settle_s", 4.0)), hold=hold)

    # -- the runner's side (Navigator) --------------------------------------------------------------
    def send(self, index: int, leg: NavLegSpec) -> None:
        with self.lock:
            self.generation += 1
            generation, self.goal_sent = self.generation, False
            self.state = (PENDING, f"waiting for the move_base action server {self.action_name}")
            if self.client is None:
                self.client = actionlib.SimpleActionClient(self.action_name, MoveBaseAction)
        threading.Thread(target=self._send, args=(generation, leg), daemon=True,
                         name=f"navigate_to-{index}").start()

    def poll(self) -> Tuple[str, str]:
        with self.lock:
            state, generation, handed = self.state, self.generation, self.handed == self.generation
        # SimpleActionClient drops a transition that arrives before send_goal returns (it is not tracking
        # that goal yet): a goal still pending here reads the client's state, outside self.lock (the
        # client's callbacks take its own lock, then self.lock).
        if state[0] == PENDING and handed and self.client.get_state() == GoalStatus.ACTIVE:
            with self.lock:
                if generation == self.generation and self.state[0] == PENDING:
                    self.state = (ACTIVE, "move_base goal active")
                state = self.state
        return state

    def cancel(self) -> None:
        with self.lock:
            self.generation += 1
            sent, self.goal_sent = self.goal_sent, False
        if sent:
            try:
                self.client.cancel_goal()
            except rospy.ROSException as exc:   # shutting down: the cancel topic is closed
                rospy.logerr(f"navigate_to leg: cancelling the move_base goal failed: {exc}")

    # -- the worker and the client's callbacks ------------------------------------------------------
    def _send(self, generation: int, leg: NavLegSpec) -> None:
        if self.settle_s > 0 and self.hold is not None and not self._settle(generation, PENDING, "the move_base goal"):
            return
        if not self.client.wait_for_server(rospy.Duration(self.server_timeout_s)):
            self._set(generation, FAILED, f"no move_base action server {self.action_name} within "
                                          f"{self.server_timeout_s:g} s (is planner_node running?)")
            return
        with self.lock:
            if generation != self.generation:    # cancelled while the server was awaited
                return
            self.goal_sent = True
            self.state = (PENDING, f"goal sent to {self.action_name}")
        rospy.loginfo(f"navigate_to leg: move_base goal ({leg.x_m:g}, {leg.y_m:g}) in {self.world_frame!r}")
        self.client.send_goal(move_base_goal(leg, self.world_frame),
                              done_cb=lambda status, _result: self._done(generation, status),
                              active_cb=lambda: self._set(generation, ACTIVE, "move_base goal active"))
        with self.lock:
            cancelled = generation != self.generation
            self.handed = generation
        if cancelled:                             # cancelled while the goal was being sent
            self.client.cancel_goal()

    def _settle(self, generation: int, state: str, before: str) -> bool:
        """The hold, then settle_s at rest (the leg's state meanwhile: state, "holding N s before ...");
        False when the leg was cancelled or replaced meanwhile."""
        self._set(generation, state, f"holding {self.settle_s:g} s before {before}")
        self.hold(f"navigate_to leg: the body settles before {before}")
        start = time.monotonic()
        repeated = 0
        while time.monotonic() - start < self.settle_s and not rospy.is_shutdown():
            with self.lock:
                if generation != self.generation:
                    return False
            if time.monotonic() - start >= repeated + 1.0:   # the driver's heartbeat, as the tracker's 1 Hz
                repeated += 1
                self.hold("")                               # repeats: not logged
            time.sleep(0.1)
        with self.lock:
            return generation == self.generation and not rospy.is_shutdown()

    def _done(self, generation: int, status: int) -> None:
        state, word = ENDS.get(status, (FAILED, f"ended in state {status}"))
        text = self.client.get_goal_status_text()
        text = f"move_base goal {word}" + (f": {text}" if text else "")
        (rospy.loginfo if state == SUCCEEDED else rospy.logwarn)(f"navigate_to leg: {text}")
        self._set(generation, state, text)

    def _set(self, generation: int, state: str, text: str) -> None:
        with self.lock:
            if generation == self.generation:
                self.state = (state, text)
                if state in (SUCCEEDED, FAILED):
                    self.goal_sent = False
