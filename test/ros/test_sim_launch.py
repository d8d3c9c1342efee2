#!/usr/bin/env python3
"""rostest: launch/sim.launch (sim_node + the C++ driver over the mocked bus + mission node) reaches
the first waypoint of a short mission, and agrees with the batch runner on the same mission.

What "agree" means (the two cannot be bit-identical: the ROS path runs in real time, with the
driver's loop jitter, bus latency and a mission that starts before the first pose arrives):
- both reach the waypoint, without roll-over and with no joint goal beyond a limit;
- the same first tracker decisions: the first two gaits the tracker commands (collapsed repeats,
  holds while waiting for poses left out), here a FAR turn in place then sidewinding;
- time from the first locomotion command to the waypoint within 50 % (or 8 s) of the batch run's;
- the ground-truth paths of the centre of mass stay within 0.5 m of each other (each point of the
  ROS path is within 0.5 m of the batch path) and end within 0.5 m.
"""
import itertools
import threading
import unittest

import numpy as np
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import String

from snake_autonomy.msg import TrackingStatus
from snake_autonomy.runs.batch import BatchRun, RunSpec

from driver_test_helpers import wait_for


def collapsed_locomotion(gaits):
    out = [g for g, _ in itertools.groupby(gaits)]
    while out and out[0] == "hold":
        out.pop(0)
    return out


class SimLaunchTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_launch_test")
        cls.lock = threading.Lock()
        cls.status, cls.path, cls.sim_status, cls.state = [], [], None, ""
        rospy.Subscriber("tracking_status", TrackingStatus, cls.on_status)
        rospy.Subscriber("ground_truth/com_pose", PoseStamped, cls.on_com)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_sim)
        rospy.Subscriber("mission/state", String, cls.on_state)
        cls.mission = rospy.get_param("~mission")
        cls.seed = int(rospy.get_param("~seed", 0))

    @classmethod
    def on_status(cls, msg):
        with cls.lock:
            cls.status.append((msg.header.stamp.to_sec(), msg.gait, msg.waypoint_reached, msg.waypoint_index))

    @classmethod
    def on_com(cls, msg):
        with cls.lock:
            cls.path.append((msg.pose.position.x, msg.pose.position.y))

    @classmethod
    def on_sim(cls, msg):
        for status in msg.status:
            if status.name == "sim: simulated robot" and status.values:
                cls.sim_status = {kv.key: kv.value for kv in status.values}

    @classmethod
    def on_state(cls, msg):
        cls.state = msg.data

    def test_reaches_the_first_waypoint_and_agrees_with_the_batch_runner(self):
        wait_for(lambda: self.state.startswith(("done", "timeout", "aborted")), 100, "the mission to end")
        self.assertTrue(self.state.startswith("done"), self.state)
        with self.lock:
            status, path = list(self.status), np.array(self.path)
        reached = [s for s in status if s[2]]
        self.assertTrue(reached, "tracking_status never reported the waypoint reached")
        wait_for(lambda: self.sim_status is not None, 5, "the simulator's status on /diagnostics")
        self.assertEqual(self.sim_status["rolled_over"], "False")
        self.assertEqual(self.sim_status["limit_violations"], "0")

        batch = BatchRun(RunSpec(mission=self.mission, seed=self.seed, feedback="mocap")).run()
        d = batch.decisions
        self.assertTrue(any(d["reached"]), batch.outcome)
        self.assertEqual(batch.extra["limit_violations"], 0)

        ros_gaits = collapsed_locomotion([s[1] for s in status])
        batch_gaits = collapsed_locomotion(d["gait"])
        rospy.loginfo(f"gaits: ROS {ros_gaits}, batch {batch_gaits}")
        self.assertEqual(ros_gaits[:2], batch_gaits[:2])

        def locomotion_time(times, gaits, reached_flags):
            t0 = next(t for t, g in zip(times, gaits) if g != "hold")
            t1 = next(t for t, r in zip(times, reached_flags) if r)
            return t1 - t0
        t_ros = locomotion_time([s[0] for s in status], [s[1] for s in status], [s[2] for s in status])
        t_batch = locomotion_time(d["t"], d["gait"], d["reached"])
        rospy.loginfo(f"time to the waypoint: ROS {t_ros:.1f} s, batch {t_batch:.1f} s")
        self.assertLessEqual(abs(t_ros - t_batch), max(8.0, 0.5 * t_batch))

        bpath = np.column_stack([batch.trajectory["x_true"], batch.trajectory["y_true"]])
        gaps = [float(np.min(np.hypot(*(bpath - p).T))) for p in path]
        rospy.loginfo(f"ROS path vs batch path: max gap {max(gaps):.2f} m, end gap "
                      f"{np.hypot(*(path[-1] - bpath[-1])):.2f} m")
        self.assertLess(max(gaps), 0.5)
        self.assertLess(float(np.hypot(*(path[-1] - bpath[-1]))), 0.5)


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_launch", SimLaunchTest)
