"""mission_node's navigate_to legs (missions/nav_leg.py) as move_base action goals: the runner's Navigator.

Action client  move_base (move_base_msgs/MoveBaseAction; planner_node serves it, move_base's conventions):
               one goal per leg, target_pose in the mission's world frame (~world_frame: the frame of the
               tracker's waypoints and poses), position (x_m, y_m), orientation heading_deg.
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
from typing import Tuple

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
    def __init__(self, world_frame: str, server_timeout_s: float, action_name: str = "move_base"):
        if not (math.isfinite(server_timeout_s) and server_timeout_s > 0):
            raise ValueError(f"~nav_server_timeout_s: must be a positive number of seconds, got {server_timeout_s!r}")
        self.world_frame, self.server_timeout_s = world_frame, float(server_timeout_s)
        self.action_name = rospy.resolve_name(action_name)
        self.client = None
        self.lock = threading.Lock()
        self.generation = 0            # counts sends and cancels: callbacks of an older goal are dropped
        self.goal_sent = False         # a goal of the current generation went to the server
        self.state: Tuple[str, str] = (PENDING, "")

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
            return self.state

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
        if cancelled:                             # cancelled while the goal was being sent
            self.client.cancel_goal()

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
