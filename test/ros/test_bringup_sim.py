#!/usr/bin/env python3
"""rostest: bringup.launch with the stand-ins (bus:=sim camera:=sim odometry:=sim world:=nav_record.yaml).

Checks: the pose remapper turns the simulated RTAB-Map's odometry into base_pose in the odom frame; the
head camera's frames reach the planner, which replans (nav/path) and commands the rectilinear gait with
curve; the driver runs the servos it commands (joint_states move); the planner's record starts its
folder in results_dir.
"""
import threading
import unittest
from pathlib import Path

import rospy
import rostest
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Path as PathMsg
from sensor_msgs.msg import JointState

from driver_test_helpers import wait_for
from snake_autonomy.msg import GaitCommand

STARTUP_S = 150.0     # MuJoCo's model and the first camera frame, on a loaded machine
STOP_GAITS = ("hold", "hold_curve")


class BringupSimTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("bringup_sim_test")
        cls.results = Path(rospy.get_param("~results_dir"))
        cls.lock = threading.Lock()
        cls.pose = cls.path = cls.moving = None
        cls.joints = []
        rospy.Subscriber("base_pose", PoseWithCovarianceStamped, cls.keep("pose"), queue_size=5)
        rospy.Subscriber("nav/path", PathMsg, cls.keep("path"), queue_size=5)
        rospy.Subscriber("gait_command", GaitCommand, cls.on_command, queue_size=20)
        rospy.Subscriber("joint_states", JointState, cls.on_joints, queue_size=50)

    @classmethod
    def keep(cls, name):
        def cb(msg):
            with cls.lock:
                setattr(cls, name, msg)
        return cb

    @classmethod
    def on_command(cls, msg):
        with cls.lock:
            if msg.gait not in STOP_GAITS and msg.curve and cls.moving is None:
                cls.moving = msg

    @classmethod
    def on_joints(cls, msg):
        with cls.lock:
            cls.joints = (cls.joints + [list(msg.position)])[-200:]

    def test_the_stack_runs_on_its_stand_ins(self):
        pose = wait_for(lambda: self.pose, STARTUP_S, "base_pose from the pose remapper")
        self.assertEqual(pose.header.frame_id, "odom")
        self.assertEqual(rospy.get_param("/pose_remapper/world_frame"), "odom")
        wait_for(lambda: self.path is not None and len(self.path.poses) > 0, 60.0, "a replan's nav/path")
        cmd = wait_for(lambda: self.moving, 60.0, "a gait command that moves")
        self.assertEqual(cmd.gait, "rectilinear")
        # the driver runs the commanded gait: the joints move by more than a degree within a few seconds
        wait_for(lambda: self.joint_spread() > 0.02, 30.0, "the joints moving")
        self.assertTrue(list(self.results.glob("*_nav_*/run.bag")), f"no record in {self.results}")

    def joint_spread(self) -> float:
        with self.lock:
            rows = list(self.joints)
        if len(rows) < 2:
            return 0.0
        return max(max(col) - min(col) for col in zip(*rows))


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "bringup_sim", BringupSimTest)
