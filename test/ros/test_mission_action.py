#!/usr/bin/env python3
"""rostest: mission_node's RunMission action (mission/run) against the fake driver.

Checks: inline waypoints run to success with feedback on the way and per-waypoint metrics in the
result; the run's bag holds the standard topics (/tf_static sent before the run, written at its
start; /diagnostics and /tf during it); cancel aborts the mission (preempted, hold sent, no more
decisions); a goal naming two missions is refused; a goal by mission file runs.
"""
import math
import os
import time
import unittest

import actionlib
import rosbag
import rospy
import rostest
import tf2_ros
from actionlib_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Pose2D, TransformStamped
from tf2_msgs.msg import TFMessage

from snake_autonomy.msg import RunMissionAction, RunMissionGoal, TrackingStatus

from mission_test_helpers import FakeDriver, wait_for


class MissionActionTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("mission_action_test")
        cls.statuses = []
        rospy.Subscriber("tracking_status", TrackingStatus, cls.statuses.append)
        cls.driver = FakeDriver()
        cls.client = actionlib.SimpleActionClient("mission/run", RunMissionAction)
        assert cls.client.wait_for_server(rospy.Duration(20)), "mission/run: no action server"
        static = TransformStamped()
        static.header.stamp = rospy.Time.now()
        static.header.frame_id, static.child_frame_id = "base_link", "test_static_frame"
        static.transform.rotation.w = 1.0
        cls.static_broadcaster = tf2_ros.StaticTransformBroadcaster()
        cls.static_broadcaster.sendTransform(static)
        cls.diag_pub = rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=10)
        cls.tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=10)

    def feedbacks(self):
        out = []
        return out, (lambda fb: out.append(fb))

    def test_1_inline_waypoints_succeed_with_feedback_metrics_and_standard_topics(self):
        goal = RunMissionGoal(name="inline_test", waypoints=[Pose2D(x=1.0, y=0.0, theta=0.0),
                                                             Pose2D(x=2.0, y=0.0, theta=0.0)])
        with self.driver.lock:
            self.driver.x = self.driver.y = self.driver.yaw = 0.0
        fbs, on_fb = self.feedbacks()
        self.client.send_goal(goal, feedback_cb=on_fb)
        deadline = time.monotonic() + 30
        while self.client.get_state() in (GoalStatus.PENDING, GoalStatus.ACTIVE) and time.monotonic() < deadline:
            array = DiagnosticArray(status=[DiagnosticStatus(name="test: alive", level=DiagnosticStatus.OK)])
            array.header.stamp = rospy.Time.now()
            self.diag_pub.publish(array)
            t = TransformStamped()
            t.header.stamp = rospy.Time.now()
            t.header.frame_id, t.child_frame_id = "odom", "test_moving_frame"
            t.transform.rotation.w = 1.0
            self.tf_pub.publish(TFMessage(transforms=[t]))
            time.sleep(0.05)
        self.assertEqual(self.client.get_state(), GoalStatus.SUCCEEDED, self.client.get_goal_status_text())
        result = self.client.get_result()
        self.assertEqual(result.mission, "inline_test")
        self.assertEqual(result.state, "done")
        self.assertEqual(result.waypoints_reached, 2)
        self.assertEqual([w.reached for w in result.waypoints], [True, True])
        self.assertTrue(all(w.final_distance_m <= 0.35 for w in result.waypoints))
        self.assertTrue(0 < result.waypoints[0].time_to_reach_s < result.waypoints[1].time_to_reach_s)
        self.assertGreater(result.path_length_m, 1.5)
        self.assertTrue(fbs, "no feedback")
        self.assertEqual({fb.num_waypoints for fb in fbs}, {2})
        self.assertIn(1, [fb.waypoint_index for fb in fbs])
        self.assertTrue(any(fb.gait == "sidewind" and math.isfinite(fb.distance) for fb in fbs))

        bag_path = os.path.join(result.run_dir, "run.bag")
        wait_for(lambda: os.path.isfile(os.path.join(result.run_dir, "metrics.json")), 10, "the results")
        with rosbag.Bag(bag_path) as bag:
            topics = {}
            for topic, msg, _t in bag.read_messages(topics=["/tf_static", "/tf", "/diagnostics"]):
                topics.setdefault(topic, []).append(msg)
        self.assertIn("test_static_frame", [t.child_frame_id for m in topics.get("/tf_static", [])
                                            for t in m.transforms])
        self.assertIn("test_moving_frame", [t.child_frame_id for m in topics.get("/tf", []) for t in m.transforms])
        self.assertIn("test: alive", [s.name for m in topics.get("/diagnostics", []) for s in m.status])

    def test_2_cancel_aborts_the_mission_and_holds(self):
        with self.driver.lock:
            self.driver.x, self.driver.y, self.driver.yaw = -3.0, 0.0, 0.0   # far from the waypoint
        fbs, on_fb = self.feedbacks()
        self.client.send_goal(RunMissionGoal(waypoints=[Pose2D(x=5.0, y=0.0, theta=0.0)]), feedback_cb=on_fb)
        wait_for(lambda: any(fb.gait == "sidewind" for fb in fbs), 10, "sidewinding feedback")
        self.client.cancel_goal()
        self.assertTrue(self.client.wait_for_result(rospy.Duration(10)), "no result after cancel")
        self.assertEqual(self.client.get_state(), GoalStatus.PREEMPTED)
        result = self.client.get_result()
        self.assertEqual(result.state, "aborted")
        self.assertIn("cancelled", result.outcome)
        self.assertEqual(result.waypoints_reached, 0)
        self.assertFalse(result.waypoints[0].reached)
        wait_for(lambda: self.driver.gait == "hold", 5, "hold after cancel")
        n = len(self.statuses)
        until = time.monotonic() + 1.0
        while time.monotonic() < until:   # the tracker runs at 5 Hz: a live mission would decide again
            time.sleep(0.05)
        self.assertTrue(all(s.gait == "hold" for s in self.statuses[n:]))
        self.assertEqual(self.driver.gait, "hold")

    def test_3_goal_with_two_missions_is_refused(self):
        self.client.send_goal(RunMissionGoal(mission="straight", waypoints=[Pose2D(x=1.0)]))
        self.assertTrue(self.client.wait_for_result(rospy.Duration(10)))
        self.assertEqual(self.client.get_state(), GoalStatus.ABORTED)
        self.assertIn("exactly one of mission, mission_yaml, waypoints", self.client.get_result().outcome)
        self.assertEqual(self.client.get_result().state, "refused")

    def test_4_goal_by_mission_file_runs(self):
        with self.driver.lock:
            self.driver.x = self.driver.y = self.driver.yaw = 0.0
        self.client.send_goal(RunMissionGoal(mission=rospy.get_param("~mission_file")))
        self.assertTrue(self.client.wait_for_result(rospy.Duration(30)))
        self.assertEqual(self.client.get_state(), GoalStatus.SUCCEEDED, self.client.get_goal_status_text())
        self.assertEqual(self.client.get_result().mission, "straight")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "mission_action", MissionActionTest)
