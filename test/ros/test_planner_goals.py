#!/usr/bin/env python3
"""rostest: planner_node takes its goals the ROS way, move_base's conventions (planner_goals.test).

The test is the robot's other nodes (camera_info, depth frames of a flat floor at 4 Hz, base poses at
20 Hz in frame map, moved by the test: a teleport into the goal's disc stands for the drive) and a
navigation user: without a goal the planner holds; a goal on move_base_simple/goal in another frame
(a static transform) is transformed, shown on nav/goal and moves the robot (rectilinear, curve=true);
a move_base action goal gets feedback and SUCCEEDED once base_link is inside its disc, and the planner
commands the stop gait (hold_curve); a second action goal preempts the first; a cancel preempts the goal
and the planner holds within two ticks; a goal in a frame tf does not know is refused with a warning
naming both frames (an action goal: ABORTED) and the robot does not move.
"""
import threading
import unittest

import actionlib
import numpy as np
import rospy
import rostest
import tf2_ros
from actionlib_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, TransformStamped
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import CameraInfo, Image
from snake_autonomy.msg import GaitCommand
from snake_autonomy.nodes.image_msgs import to_camera_info, to_image
from visualization_msgs.msg import Marker

from driver_test_helpers import wait_for

TICK_S = 0.5                 # the planner commands at ~rate_hz 2
FORWARD, STOP = "rectilinear", "hold_curve"     # config/nav.yaml gaits.forward, gaits.stop
WORLD, OTHER = "map", "goal_frame"               # OTHER: map + (1, 0, 0), a static transform the test sends


def floor_depth(k, T_ground_optical, max_m=4.0):
    """Depth (m) of a flat floor z = 0 seen by a camera at T_ground_optical; 0 where none nearer than max_m."""
    from snake_autonomy.planning.rectilinear.collision_check import floor_rays
    v, u = np.mgrid[0:k.height, 0:k.width]
    _, s, down = floor_rays(u.ravel(), v.ravel(), k.K(), T_ground_optical)   # s: the depth (rays at z = 1)
    return np.where(down & (s < max_m), s, 0.0).reshape(k.height, k.width).astype(np.float32)


class PlannerGoalsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("planner_goals_test")
        from snake_autonomy import _core
        from snake_autonomy.paths import config_path
        from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera
        cfg = NavConfig.from_yaml()
        cls.radius = _core.RobotModel.from_yaml(str(config_path("robots", "cobra.yaml"))).link_radius_m
        cls.depth = floor_depth(cfg.intrinsics, T_ground_camera(cfg.mount, cls.radius))
        cls.lock = threading.Lock()
        cls.commands, cls.planner, cls.warnings, cls.marker = [], {}, [], None
        cls.xy = (0.0, 0.0)                              # where the test puts base_link
        cls.tf = tf2_ros.StaticTransformBroadcaster()
        t = TransformStamped()
        t.header.stamp, t.header.frame_id, t.child_frame_id = rospy.Time.now(), WORLD, OTHER
        t.transform.translation.x, t.transform.rotation.w = 1.0, 1.0
        cls.tf.sendTransform(t)
        cls.pub_info = rospy.Publisher("camera/color/camera_info", CameraInfo, queue_size=1, latch=True)
        cls.pub_info.publish(to_camera_info(cfg.intrinsics, rospy.Time.now(), "camera_color_optical_frame"))
        cls.pub_depth = rospy.Publisher("camera/depth/image_rect_raw", Image, queue_size=2)
        cls.pub_pose = rospy.Publisher("base_pose", PoseWithCovarianceStamped, queue_size=5)
        cls.pub_goal = rospy.Publisher("move_base_simple/goal", PoseStamped, queue_size=1)
        cls.listen("gait_command", GaitCommand, lambda m: cls.commands.append((rospy.get_time(), m.gait)))
        cls.listen("/diagnostics", DiagnosticArray, cls.keep_diagnostics)
        cls.listen("/rosout", Log, lambda m: cls.warnings.append(m.msg) if (m.name, m.level) == ("/planner", Log.WARN)
                   else None)
        cls.listen("nav/goal", Marker, lambda m: setattr(cls, "marker", m))
        cls.timer = rospy.Timer(rospy.Duration(0.05), cls.stream)
        cls.client = cls.action_client()

    @staticmethod
    def action_client():
        client = actionlib.SimpleActionClient("move_base", MoveBaseAction)
        assert client.wait_for_server(rospy.Duration(60.0)), "no move_base action server"
        return client

    @classmethod
    def stream(cls, _event):
        """Base poses at 20 Hz (at cls.xy) and depth frames at 4 Hz."""
        now = rospy.Time.now()
        m = PoseWithCovarianceStamped()
        m.header.stamp, m.header.frame_id = now, WORLD
        m.pose.pose.position.x, m.pose.pose.position.y = cls.xy
        m.pose.pose.position.z = cls.radius
        m.pose.pose.orientation.w = 1.0
        cls.pub_pose.publish(m)
        if now.to_nsec() // 50_000_000 % 5 == 0:
            cls.pub_depth.publish(to_image(cls.depth, "32FC1", now, "camera_depth_optical_frame"))

    @classmethod
    def listen(cls, topic, msg_type, keep):
        """Subscribes topic; keep(msg) runs under cls.lock (what the test cases read)."""
        def callback(msg):
            with cls.lock:
                keep(msg)
        rospy.Subscriber(topic, msg_type, callback, queue_size=50)

    @classmethod
    def keep_diagnostics(cls, msg):
        """The planner's navigation status: key -> value."""
        cls.planner = next(({kv.key: kv.value for kv in st.values} for st in msg.status
                            if st.name.endswith("navigation")), cls.planner)

    # -- helpers ---------------------------------------------------------------------------------
    def until(self, cond, timeout_s, what):
        """Waits for cond; a failure names what and the planner's diagnostics at the time."""
        try:
            return wait_for(cond, timeout_s, what)
        except AssertionError as exc:
            with self.lock:
                raise AssertionError(f"{exc}; planner diagnostics: {self.planner}") from None

    def diag(self, key, default=""):
        with self.lock:
            return self.planner.get(key, default)

    def gaits_since(self, since):
        with self.lock:
            return [(t, gait) for t, gait in self.commands if t >= since]

    def moving_since(self, since):
        return any(g == FORWARD for _, g in self.gaits_since(since))

    def holding_since(self, since, ticks=2):
        gaits = [g for _, g in self.gaits_since(since)]
        return len(gaits) >= ticks and all(g == STOP for g in gaits)

    @staticmethod
    def pose(x, y, frame=WORLD):
        p = PoseStamped()
        p.header.stamp, p.header.frame_id = rospy.Time.now(), frame
        p.pose.position.x, p.pose.position.y = x, y
        p.pose.orientation.w = 1.0
        return p

    def send(self, client, x, y, frame=WORLD, feedback=None):
        client.send_goal(MoveBaseGoal(target_pose=self.pose(x, y, frame)), feedback_cb=feedback)

    def state_is(self, client, *states):
        return lambda: client.get_state() in states

    # -- the cases, in order (one planner for all) ------------------------------------------------
    def test_1_without_a_goal_the_planner_holds(self):
        self.until(lambda: self.diag("state") == "no_goal", 30.0, "state no_goal on a free floor")
        t = rospy.get_time()
        self.until(lambda: self.holding_since(t), 5.0, f"the stop gait {STOP}")
        self.assertEqual(self.diag("goal"), "none")

    def test_2_a_goal_on_move_base_simple_goal_moves_the_robot(self):
        t = rospy.get_time()
        self.pub_goal.publish(self.pose(1.0, 0.0, OTHER))          # (2, 0) in map
        self.until(lambda: self.moving_since(t), 10.0, f"the forward gait {FORWARD} after a topic goal")
        with self.lock:
            m = self.marker
        self.assertEqual((m.header.frame_id, m.action, m.type), (WORLD, Marker.ADD, Marker.CYLINDER))
        self.assertAlmostEqual(m.pose.position.x, 2.0, places=6)
        self.assertAlmostEqual(m.scale.x, 0.4, places=6)                  # 2 x ~goal_radius_m
        self.until(lambda: "move_base_simple/goal" in self.diag("goal"), 5.0, "the topic goal on /diagnostics")

    def test_3_an_action_goal_gets_feedback_and_succeeds_inside_its_disc(self):
        feedback = []
        t = rospy.get_time()
        self.send(self.client, 2.0, 0.5, feedback=feedback.append)
        self.until(lambda: len(feedback) >= 2, 5.0, "action feedback")
        self.assertEqual(feedback[-1].base_position.header.frame_id, WORLD)
        self.assertEqual(self.client.get_state(), GoalStatus.ACTIVE)
        self.until(lambda: self.moving_since(t), 5.0, "moving to the action goal")
        type(self).xy = (1.9, 0.45)                                  # inside the disc (radius 0.2)
        self.assertTrue(self.client.wait_for_result(rospy.Duration(5.0)), "no result inside the goal's disc")
        self.assertEqual(self.client.get_state(), GoalStatus.SUCCEEDED, self.client.get_goal_status_text())
        t_done = rospy.get_time()
        self.until(lambda: self.holding_since(t_done), 5.0, f"the stop gait {STOP} at the goal")
        self.until(lambda: self.diag("state") == "goal_reached", 5.0, "state goal_reached")
        type(self).xy = (0.0, 0.0)

    def test_4_a_second_action_goal_preempts_the_first(self):
        first, second = self.client, self.action_client()
        self.send(first, 3.0, 0.0)
        self.until(self.state_is(first, GoalStatus.ACTIVE), 5.0, "the first goal active")
        t = rospy.get_time()
        self.send(second, 3.0, 0.5)
        self.until(self.state_is(first, GoalStatus.PREEMPTED), 5.0, "the first goal preempted")
        self.until(self.state_is(second, GoalStatus.ACTIVE), 5.0, "the second goal active")
        self.until(lambda: self.moving_since(t), 5.0, "moving to the second goal")
        type(self).second = second
        self.until(lambda: "(3.000, 0.500)" in self.diag("goal"), 5.0, "the second goal on /diagnostics")

    def test_5_cancel_preempts_and_the_planner_holds_within_two_ticks(self):
        second = self.second
        self.until(lambda: self.moving_since(rospy.get_time() - 1.0), 5.0, "moving before the cancel")
        t = rospy.get_time()
        second.cancel_goal()
        self.until(self.state_is(second, GoalStatus.PREEMPTED, GoalStatus.RECALLED), 5.0, "the goal canceled")
        self.until(lambda: self.holding_since(t + 2 * TICK_S), 5.0, f"the stop gait {STOP}")
        first_stop = min(tc for tc, g in self.gaits_since(t) if g == STOP)
        self.assertLessEqual(first_stop - t, 2 * TICK_S + 0.2, "no stop within two ticks of the cancel")
        self.until(lambda: self.diag("state") == "no_goal", 5.0, "state no_goal")

    def test_6_a_goal_in_an_unknown_frame_is_refused(self):
        refused = int(self.diag("goals_refused", "0"))
        t = rospy.get_time()
        self.pub_goal.publish(self.pose(2.0, 0.0, "nowhere"))
        self.until(lambda: any("'nowhere'" in w and f"'{WORLD}'" in w for w in self.warnings), 5.0,
                   "a warning naming both frames")
        self.send(self.client, 2.0, 0.0, "nowhere")
        self.assertTrue(self.client.wait_for_result(rospy.Duration(5.0)))
        self.assertEqual(self.client.get_state(), GoalStatus.ABORTED)
        self.assertIn("'nowhere'", self.client.get_goal_status_text())
        self.until(lambda: int(self.diag("goals_refused", "0")) >= refused + 2, 5.0, "two goals refused")
        rospy.sleep(3 * TICK_S)
        self.assertTrue(self.holding_since(t, ticks=3), f"moved: {self.gaits_since(t)}")
        self.until(lambda: self.diag("goal") == "none", 5.0, "no goal on /diagnostics")
        self.assertEqual(self.diag("node_errors"), "0")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "planner_goals", PlannerGoalsTest)
