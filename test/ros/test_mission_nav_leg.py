#!/usr/bin/env python3
"""rostest: mission_node's navigate_to legs and RunMission goals with a frame (mission_nav_leg.test).

The test is the fake driver (mission_test_helpers) and a fake move_base server (actionlib, made after the
first test: a goal with x < 0 is ABORTED, one with x > 10 runs until cancelled, any other teleports the
fake driver into it and SUCCEEDS).
Checks: with no move_base server a leg aborts the mission naming the leg and the action; a mission
tracker waypoint -> leg -> tracker waypoint ends done, the move_base goal in the world frame, feedback
carrying the leg, no gait command from the mission node while the leg runs; an ABORTED leg aborts the
mission with the server's reason; inline waypoints in frame_id are transformed with tf2 (a static
transform), and a frame tf does not know refuses the goal naming the frame; cancelling the RunMission
goal while a leg runs cancels the move_base goal.
"""
import math
import threading
import time
import unittest

import actionlib
import rospy
import rostest
import tf2_ros
from actionlib_msgs.msg import GoalStatus
from geometry_msgs.msg import Pose2D, TransformStamped
from move_base_msgs.msg import MoveBaseAction

from snake_autonomy.msg import RunMissionAction, RunMissionGoal

from mission_test_helpers import FakeDriver, wait_for

WORLD, OTHER = "odom", "test_frame"     # OTHER: odom + (1, 0, 0) turned +90 deg, a static transform
LEG_MISSION = """
name: nav_leg_test
time_limit_s: 60
waypoints:
  - [0.6, 0.0, 0.0]
  - {navigate_to: {x_m: 1.5, y_m: 1.0}}
  - [2.1, 1.0, 0.0]
"""
FAR_LEG = """
name: nav_leg_far
waypoints:
  - {navigate_to: {x_m: 50.0, y_m: 0.0}}
"""
FAILING_LEG = """
name: nav_leg_aborted
waypoints:
  - {navigate_to: {x_m: -1.0, y_m: 0.0}}
  - [0.0, 0.0, 0.0]
"""


class FakeMoveBase:
    """move_base as the planner serves it, reduced to its outcome: x < 0 ABORTED, x > 10 driving until
    cancelled (PREEMPTED), else the driver is put into the goal and the goal SUCCEEDED. Records each goal
    with its accept and end times."""

    def __init__(self, driver):
        self.driver, self.goals, self.lock = driver, [], threading.Lock()
        self.server = actionlib.SimpleActionServer("move_base", MoveBaseAction, execute_cb=self.execute,
                                                   auto_start=False)
        self.server.start()

    def execute(self, goal):
        record = {"goal": goal, "accepted": rospy.Time.now()}
        with self.lock:
            self.goals.append(record)
        time.sleep(0.6)                  # a few of the mission's ticks while the "planner" drives
        p = goal.target_pose.pose.position
        while p.x > 10 and not rospy.is_shutdown():
            if self.server.is_preempt_requested():
                record["preempted"] = rospy.Time.now()
                self.server.set_preempted(text="cancelled")
                return
            time.sleep(0.05)
        if p.x < 0:
            record["ended"] = rospy.Time.now()
            self.server.set_aborted(text="no free arc (test)")
            return
        with self.driver.lock:
            self.driver.x, self.driver.y, self.driver.yaw = p.x, p.y, 0.0
        time.sleep(0.3)
        record["ended"] = rospy.Time.now()
        self.server.set_succeeded(text="inside the goal's disc (test)")


class MissionNavLegTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("mission_nav_leg_test")
        cls.driver = FakeDriver()
        cls.move_base = None
        cls.client = actionlib.SimpleActionClient("mission/run", RunMissionAction)
        assert cls.client.wait_for_server(rospy.Duration(20)), "mission/run: no action server"
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id, t.child_frame_id = WORLD, OTHER
        t.transform.translation.x = 1.0
        t.transform.rotation.z, t.transform.rotation.w = math.sin(math.pi / 4), math.cos(math.pi / 4)
        cls.static_broadcaster = tf2_ros.StaticTransformBroadcaster()
        cls.static_broadcaster.sendTransform(t)

    def place(self, x, y, yaw_deg):
        with self.driver.lock:
            self.driver.x, self.driver.y, self.driver.yaw = x, y, math.radians(yaw_deg)

    def run_goal(self, goal, timeout_s=30):
        feedbacks = []
        self.client.send_goal(goal, feedback_cb=feedbacks.append)
        self.assertTrue(self.client.wait_for_result(rospy.Duration(timeout_s)), "no result")
        return self.client.get_state(), self.client.get_result(), feedbacks

    def fake_move_base(self):
        if MissionNavLegTest.move_base is None:
            MissionNavLegTest.move_base = FakeMoveBase(self.driver)
        return MissionNavLegTest.move_base

    def test_1_without_move_base_a_leg_aborts_the_mission_naming_it(self):
        self.place(0.0, 0.0, 0.0)
        state, result, _ = self.run_goal(RunMissionGoal(mission_yaml=FAILING_LEG))
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertEqual(result.state, "aborted")
        self.assertIn("waypoints[0] navigate_to (-1, 0): no move_base action server /move_base within 2 s",
                      result.outcome)
        wait_for(lambda: self.driver.gait == "hold", 5, "hold after the abort")

    def test_2_a_leg_drives_move_base_and_the_mission_ends_done(self):
        server = self.fake_move_base()
        self.place(0.0, 0.0, 0.0)
        n_commands = len(self.driver.commands)
        state, result, feedbacks = self.run_goal(RunMissionGoal(mission_yaml=LEG_MISSION))
        self.assertEqual(state, GoalStatus.SUCCEEDED, result.outcome)
        self.assertEqual((result.state, result.waypoints_reached), ("done", 3))
        self.assertEqual([w.reached for w in result.waypoints], [True, True, True])
        with server.lock:
            self.assertEqual(len(server.goals), 1)
            leg = server.goals[0]
        target = leg["goal"].target_pose
        self.assertEqual(target.header.frame_id, WORLD)
        self.assertEqual((target.pose.position.x, target.pose.position.y), (1.5, 1.0))
        on_leg = [fb for fb in feedbacks if fb.leg == "navigate_to"]
        self.assertTrue(on_leg, "no feedback of the leg")
        self.assertEqual({fb.waypoint_index for fb in on_leg if not fb.leg_state.startswith("reached")}, {1})
        self.assertTrue(any(fb.leg_state.startswith("reached: move_base goal succeeded") for fb in on_leg))
        self.assertIn("track", {fb.leg for fb in feedbacks})
        during = [c for c in self.driver.commands[n_commands:]
                  if leg["accepted"] < c.header.stamp < leg["ended"]]
        self.assertEqual(during, [], "the mission node commanded gaits while move_base drove")
        self.assertEqual(self.driver.gait, "hold")

    def test_3_an_aborted_leg_aborts_the_mission_with_the_reason(self):
        self.fake_move_base()
        state, result, _ = self.run_goal(RunMissionGoal(mission_yaml=FAILING_LEG))
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertEqual((result.state, result.waypoints_reached), ("aborted", 0))
        self.assertIn("waypoints[0] navigate_to (-1, 0): move_base goal aborted: no free arc (test)", result.outcome)
        wait_for(lambda: self.driver.gait == "hold", 5, "hold after the abort")

    def test_4_inline_waypoints_in_another_frame_are_transformed(self):
        self.place(1.0, 0.0, 90.0)       # OTHER's (0.5, 0) heading 0 is odom's (1.0, 0.5) heading 90 deg
        goal = RunMissionGoal(name="framed", frame_id=OTHER, waypoints=[Pose2D(x=0.5, y=0.0, theta=0.0)])
        state, result, _ = self.run_goal(goal)
        self.assertEqual(state, GoalStatus.SUCCEEDED, result.outcome)
        wp = result.waypoints[0]
        self.assertAlmostEqual(wp.x_m, 1.0, places=6)
        self.assertAlmostEqual(wp.y_m, 0.5, places=6)
        self.assertAlmostEqual(wp.heading_deg, 90.0, places=6)

    def test_5_a_frame_tf_does_not_know_refuses_the_goal_naming_it(self):
        goal = RunMissionGoal(frame_id="no_such_frame", waypoints=[Pose2D(x=0.5, y=0.0, theta=0.0)])
        state, result, _ = self.run_goal(goal)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertEqual(result.state, "refused")
        self.assertIn("frame_id 'no_such_frame': no transform to the world frame 'odom'", result.outcome)

    def test_6_cancelling_the_mission_cancels_the_leg_goal(self):
        server = self.fake_move_base()
        feedbacks = []
        self.client.send_goal(RunMissionGoal(mission_yaml=FAR_LEG), feedback_cb=feedbacks.append)
        wait_for(lambda: any(fb.leg_state == "move_base goal active" for fb in feedbacks), 10, "the leg active")
        self.client.cancel_goal()
        self.assertTrue(self.client.wait_for_result(rospy.Duration(10)), "no result after cancel")
        self.assertEqual(self.client.get_state(), GoalStatus.PREEMPTED)
        self.assertEqual(self.client.get_result().state, "aborted")
        with server.lock:
            leg = server.goals[-1]
        self.assertEqual(leg["goal"].target_pose.pose.position.x, 50.0)
        wait_for(lambda: "preempted" in leg, 5, "the move_base goal cancelled")
        wait_for(lambda: self.driver.gait == "hold", 5, "hold after the cancel")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "mission_nav_leg", MissionNavLegTest)
