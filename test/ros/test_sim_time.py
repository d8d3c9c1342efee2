#!/usr/bin/env python3
"""rostest: sim.launch with use_sim_time:=true completes a short mission on the simulator's clock.

Checks: the mission ends "done"; its run started at a /clock time (the mission node waited for the
first /clock: a start at time zero would have fired the time limit at once), the CoM poses of the bag
carry stamps of the same clock; the run's bag holds /tf (the driver's world frame -> base_link),
/tf_static (robot_state_publisher's fixed joints, e.g. the camera, written at the run's start) and
/diagnostics.
"""
import glob
import json
import os
import time
import unittest

import rosbag
import rospy
import rostest
from std_msgs.msg import String

from mission_test_helpers import wait_for


class SimTimeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_time_test")
        cls.state = ""
        cls.started_wall = time.time()
        rospy.Subscriber("mission/state", String, cls.on_state)

    @classmethod
    def on_state(cls, msg):
        cls.state = msg.data

    def test_mission_completes_on_sim_time_and_its_bag_replays(self):
        self.assertTrue(rospy.get_param("/use_sim_time"))
        wait_for(lambda: self.state.startswith(("done", "timeout", "aborted")), 160, "the mission to end")
        self.assertTrue(self.state.startswith("done"), self.state)
        results = rospy.get_param("~results_dir")

        def this_run():
            runs = [d for d in glob.glob(os.path.join(results, "*_sim_short*"))
                    if os.path.getmtime(d) >= self.started_wall - 5]
            return sorted(runs, key=os.path.getmtime)[-1] if runs else None
        wait_for(lambda: this_run() and os.path.isfile(os.path.join(this_run(), "yaw_error_vs_distance.png")),
                 60, "the run's results")
        run_dir = this_run()
        metrics = json.load(open(os.path.join(run_dir, "metrics.json")))
        self.assertTrue(metrics["outcome"].startswith("done"), metrics["outcome"])
        t_start = metrics["meta"]["t_start"]
        self.assertGreater(t_start, 0.0)
        frames = {}
        with rosbag.Bag(os.path.join(run_dir, "run.bag")) as bag:
            com_stamps = [m.header.stamp.to_sec() for topic, m, _t in bag.read_messages()
                          if topic.endswith("/com_pose")]
            for topic, msg, _t in bag.read_messages(topics=["/tf", "/tf_static", "/diagnostics"]):
                if topic == "/diagnostics":
                    frames.setdefault(topic, set()).update(s.name for s in msg.status)
                else:
                    frames.setdefault(topic, set()).update(t.child_frame_id for t in msg.transforms)
        rospy.loginfo(f"run {run_dir}: t_start {t_start:.2f} s; recorded {sorted(frames)}; "
                      f"static frames {sorted(frames.get('/tf_static', []))}")
        self.assertTrue(com_stamps, "no com_pose in the bag")
        self.assertLess(abs(com_stamps[0] - t_start), 10.0, "com_pose stamps and the run's start on different clocks")
        self.assertIn("base_link", frames.get("/tf", set()))
        self.assertIn("camera_link", frames.get("/tf_static", set()))
        self.assertTrue(frames.get("/diagnostics"), "no /diagnostics in the bag")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_time", SimTimeTest)
