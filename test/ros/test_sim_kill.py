#!/usr/bin/env python3
"""rostest: launch/sim.launch with a long mission; once the simulated robot sidewinds, the mission
node is killed with SIGKILL (no shutdown hook, no final hold). The driver must stop on its own: its
command lifetime (command_timeout_s) expires, /diagnostics says why, the mocked bus's goals stop
changing and the robot stops (before, it kept sidewinding, 2.59 m in 10 s)."""
import math
import os
import signal
import threading
import time
import unittest
from xmlrpc.client import ServerProxy

import rosgraph
import rosnode
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped

from driver_test_helpers import LOCO, wait_for
from snake_autonomy.sim.mock_servo_bus import MockBusClient


class SimKillTest(unittest.TestCase):
    def setUp(self):
        rospy.init_node("sim_kill_test")
        self.lock = threading.Lock()
        self.loco = None
        self.com = []
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag)
        rospy.Subscriber("ground_truth/com_pose", PoseStamped, self.on_com)

    def on_diag(self, msg):
        for s in msg.status:
            if s.name == LOCO:
                with self.lock:
                    self.loco = s

    def on_com(self, msg):
        with self.lock:
            self.com.append((time.monotonic(), msg.pose.position.x, msg.pose.position.y))

    def value(self, key):
        with self.lock:
            s = self.loco
        return next((kv.value for kv in s.values if kv.key == key), None) if s else None

    def travelled(self, since):
        """Distance of the true centre of mass between the first sample after `since` and the last."""
        with self.lock:
            pts = [(x, y) for t, x, y in self.com if t >= since]
        return math.hypot(pts[-1][0] - pts[0][0], pts[-1][1] - pts[0][1]) if len(pts) > 1 else 0.0

    def test_killed_mission_node_stops_the_robot(self):
        wait_for(lambda: self.com and self.value("gait") == "sidewind" and self.value("state") == "running", 120,
                 "the robot to sidewind")
        t_moving = time.monotonic()
        wait_for(lambda: self.travelled(t_moving) > 0.15, 20, "the robot to move 0.15 m")
        master = rosgraph.Master(rospy.get_name())
        pid = ServerProxy(rosnode.get_api_uri(master, "/mission")).getPid(rospy.get_name())[2]
        timeout_s = float(self.value("command_timeout_s"))
        os.kill(pid, signal.SIGKILL)
        killed = time.monotonic()
        wait_for(lambda: self.loco.message.startswith("holding: no gait command"), timeout_s + 4.0,
                 "the driver to hold after its command lifetime")
        elapsed = time.monotonic() - killed
        rospy.loginfo(f"held {elapsed:.2f} s after the mission node was killed (command_timeout_s {timeout_s})")
        self.assertLessEqual(elapsed, timeout_s + 1.0 + 1.0 + 0.5)  # lifetime + command period + diag period
        # Held: over the next two seconds the mocked bus's goals do not change and the robot stays.
        bus = MockBusClient(rospy.get_param("~port") + ".ctl")
        t_held = time.monotonic()
        seen = set()
        try:
            while time.monotonic() - t_held < 2.0:
                seen.add(tuple(sorted((k, v["goal_ticks"]) for k, v in bus.call("state").items())))
                time.sleep(0.05)
        finally:
            bus.close()
        self.assertEqual(len(seen), 1, "the mocked bus's goals changed while the driver held")
        self.assertLess(self.travelled(t_held), 0.05)


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_kill", SimKillTest)
