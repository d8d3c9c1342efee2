#!/usr/bin/env python3
"""rostest: goals the ROS way on the simulated robot in physics (sim_nav_goals.test: the 12-link robot
on test/ros/worlds/nav_record.yaml; test_planner_goals.py checks the same on a stub floor with poses
the test moves itself).

In order: an action goal far ahead is taken and the robot moves; a goal on move_base_simple/goal
(rviz's "2D Nav Goal") preempts it and is reached (the planner's state goal_reached, base_link inside
its disc by ground truth); a second action goal moves the robot again and a cancel preempts it: the
planner sends only its stop gait from the second tick on and base_link stays put (ground truth).
Measured: 33-36 s wall; the topic goal 0.3 m ahead reached after ~12 s of crawling."""
import math
import threading
import unittest

import actionlib
import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal

from snake_autonomy.msg import GaitCommand

from driver_test_helpers import diagnostic_values, wait_for

WORLD = "map"
ROBOT = "chang_rectilinear"
RADIUS_M = 0.2                                   # planner_node's ~goal_radius_m for goals that arrive
TICK_S = 0.5                                     # planner_node's ~rate_hz 2
HELD_DRIFT_M = 0.005                             # base_link's shift over 3 s once held (a stop moves it ~1 cm)


class SimNavGoalsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_nav_goals_test")
        cls.lock = threading.Lock()
        cls.commands, cls.planner, cls.truth = [], {}, None
        rospy.Subscriber("gait_command", GaitCommand, cls.on_command, queue_size=50)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag, queue_size=20)
        rospy.Subscriber("ground_truth/base_pose", PoseStamped, cls.on_truth, queue_size=5)
        cls.pub_goal = rospy.Publisher("move_base_simple/goal", PoseStamped, queue_size=1, latch=True)
        from snake_autonomy.paths import config_path
        from snake_autonomy.planning.rectilinear.config import NavConfig
        gaits = NavConfig.from_yaml(config_path(f"nav_{ROBOT}.yaml")).gaits
        cls.forward, cls.stop = gaits.forward, gaits.stop

    @classmethod
    def on_command(cls, msg):
        if msg._connection_header["callerid"] == "/planner":
            with cls.lock:
                cls.commands.append((rospy.get_time(), msg.gait))

    @classmethod
    def on_diag(cls, msg):
        values = diagnostic_values(msg, "navigation")
        if values is not None:
            with cls.lock:
                cls.planner = values

    @classmethod
    def on_truth(cls, msg):
        with cls.lock:
            cls.truth = (msg.pose.position.x, msg.pose.position.y)

    def xy(self):
        with self.lock:
            return self.truth

    def until(self, cond, timeout_s, what):
        try:
            return wait_for(cond, timeout_s, what)
        except AssertionError as exc:
            with self.lock:
                raise AssertionError(f"{exc}; planner diagnostics: {self.planner}; base_link {self.truth}") from None

    def gaits_since(self, since):
        with self.lock:
            return [g for t, g in self.commands if t >= since]

    def moved_from(self, start, by_m=0.005):
        now = self.xy()
        return now is not None and math.dist(now, start) > by_m

    @staticmethod
    def pose(x, y):
        p = PoseStamped()
        p.header.stamp, p.header.frame_id = rospy.Time.now(), WORLD
        p.pose.position.x, p.pose.position.y, p.pose.orientation.w = x, y, 1.0
        return p

    def test_goals_from_the_action_and_rviz_reached_preempted_and_cancelled_in_physics(self):
        client = actionlib.SimpleActionClient("move_base", MoveBaseAction)
        # MuJoCo's model and the planner's first camera frame: up to a minute or two on a loaded machine
        self.assertTrue(client.wait_for_server(rospy.Duration(150.0)), "no move_base action server")
        self.until(self.xy, 60.0, "ground_truth/base_pose")

        # an action goal far ahead: taken, the robot crawls
        start, t = self.xy(), rospy.get_time()
        client.send_goal(MoveBaseGoal(target_pose=self.pose(1.2, 0.0)))
        self.until(lambda: client.get_state() == GoalStatus.ACTIVE, 10.0, "the action goal active")
        self.until(lambda: self.forward in self.gaits_since(t), 30.0, "the forward gait for the action goal")
        self.until(lambda: self.moved_from(start), 60.0, "base_link moving towards the action goal")

        # rviz's 2D Nav Goal preempts it and is reached
        sent_at = self.xy()
        goal = (sent_at[0] + RADIUS_M + 0.1, 0.0)            # 10 cm beyond its disc: a crawl to reach it
        self.pub_goal.publish(self.pose(*goal))
        self.until(lambda: client.get_state() == GoalStatus.PREEMPTED, 10.0, "the action goal preempted")
        self.until(lambda: "move_base_simple/goal" in self.planner.get("goal", ""), 10.0, "the topic goal taken")
        self.until(lambda: self.planner.get("state") == "goal_reached", 120.0, "the topic goal reached")
        self.assertLess(math.dist(self.xy(), goal), RADIUS_M, "base_link outside the goal's disc")
        self.assertGreater(math.dist(self.xy(), sent_at), 0.08, "reached without crawling to it")

        # a second action goal, then a cancel: the robot holds where it is
        client.send_goal(MoveBaseGoal(target_pose=self.pose(1.2, 0.0)))
        start, t = self.xy(), rospy.get_time()
        self.until(lambda: client.get_state() == GoalStatus.ACTIVE, 10.0, "the second action goal active")
        self.until(lambda: self.forward in self.gaits_since(t), 30.0, "the forward gait for the second goal")
        self.until(lambda: self.moved_from(start, 0.01), 60.0, "base_link 1 cm towards the second goal")
        t_cancel = rospy.get_time()
        client.cancel_goal()
        self.until(lambda: client.get_state() in (GoalStatus.PREEMPTED, GoalStatus.RECALLED), 10.0, "canceled")
        rospy.sleep(2 * TICK_S + 2.0)                       # two ticks, and the stop gait settled
        held = self.xy()
        rospy.sleep(3.0)
        late = self.gaits_since(t_cancel + 2 * TICK_S + 0.2)
        self.assertTrue(late and set(late) == {self.stop}, f"the planner's gaits after the cancel: {late}")
        self.assertLess(math.dist(self.xy(), held), HELD_DRIFT_M, (held, self.xy()))
        self.until(lambda: self.planner.get("state") == "no_goal", 5.0, "state no_goal")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_nav_goals", SimNavGoalsTest)
