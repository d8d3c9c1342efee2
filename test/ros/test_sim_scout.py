#!/usr/bin/env python3
"""rostest: a mission's scout stop through ROS (on the driver's trajectory execution).

Checks: the mission ends "done"; its metrics list one scout stop, done, with every phase in order and
the hold lasting hold_s; while raised, the head (TF world frame -> base_link, the front end of the
head module: the planner's head, frame 0; its pose is the motion-capture base pose) rose to the
planned height within 3 cm (the batch test's tolerance: servo sag and the body's slide during the
lead-in); after the lowering it is back near the ground. No gait command is sent while the trajectory owns the joints.
"""
import glob
import json
import os
import time
import unittest

import rospy
import rostest
import tf2_ros
from snake_autonomy.msg import GaitCommand
from std_msgs.msg import String

from mission_test_helpers import wait_for

PLANNED_M = 0.3


class SimScoutTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_scout_test")
        cls.state = ""
        cls.started_wall = time.time()
        cls.commands = []   # (wall time, gait)
        rospy.Subscriber("mission/state", String, cls.on_state)
        rospy.Subscriber("gait_command", GaitCommand, cls.on_cmd)
        cls.tf = tf2_ros.Buffer(rospy.Duration(30.0))
        cls.listener = tf2_ros.TransformListener(cls.tf)

    @classmethod
    def on_state(cls, msg):
        cls.state = msg.data

    @classmethod
    def on_cmd(cls, msg):
        cls.commands.append((time.time(), msg.gait))

    def head_z(self):
        world = rospy.get_param("/driver/world_frame", "odom")
        try:
            t = self.tf.lookup_transform(world, "base_link", rospy.Time(0), rospy.Duration(0.2))
        except (tf2_ros.LookupException, tf2_ros.ExtrapolationException, tf2_ros.ConnectivityException):
            return None
        return t.transform.translation.z

    def test_scout_stop_raises_holds_and_lowers_the_head_through_the_driver(self):
        heads = []   # (wall time, head z)
        deadline = time.time() + 200
        while not self.state.startswith(("done", "timeout", "aborted")) and time.time() < deadline:
            z = self.head_z()
            if z is not None:
                heads.append((time.time(), z))
            time.sleep(0.1)
        self.assertTrue(self.state.startswith("done"), self.state)
        results = rospy.get_param("~results_dir")

        def this_run():
            runs = [d for d in glob.glob(os.path.join(results, "*_sim_scout*"))
                    if os.path.getmtime(d) >= self.started_wall - 5]
            return sorted(runs, key=os.path.getmtime)[-1] if runs else None
        wait_for(lambda: this_run() and os.path.isfile(os.path.join(this_run(), "yaw_error_vs_distance.png")),
                 60, "the run's results")
        metrics = json.load(open(os.path.join(this_run(), "metrics.json")))
        scouts = metrics.get("scouts", [])
        self.assertEqual(len(scouts), 1, metrics)
        stop = scouts[0]
        self.assertEqual(stop["outcome"], "done", stop)
        phases = stop["phases"]
        self.assertEqual(list(phases), ["planning", "raising", "holding", "lowering", "done"])
        self.assertGreaterEqual(phases["lowering"] - phases["holding"], 2.0 - 1e-6)
        self.assertAlmostEqual(stop["planned_head_height_m"], PLANNED_M, delta=0.01)

        self.assertTrue(heads, "no world -> base_link transform seen")
        top = max(z for _t, z in heads)
        rospy.loginfo(f"head: highest {top:.3f} m (planned {stop['planned_head_height_m']:.3f} m), "
                      f"last {heads[-1][1]:.3f} m; {len(self.commands)} gait commands")
        self.assertLess(abs(top - stop["planned_head_height_m"]), 0.03)
        self.assertLess(heads[-1][1], 0.1, "the head was not lowered")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_scout", SimScoutTest)
