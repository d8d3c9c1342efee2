#!/usr/bin/env python3
"""rostest: `snake_autonomy calibrate --ros` on the simulated robot of launch/sim.launch.

Two steering values (+4 and +10 deg, either side of the simulated robot's straight sidewinding),
one settling and two recorded cycles each (about 20 s in real time): the command exits 0, writes
calibration.yaml whose tracker: block is within 3 deg (delta0) and 5 deg (heading offset) of
config/sim.yaml's (the batch simulator's calibration over five seeds: +7.4, +92.4), and the last
gait command on the topic is the hold. Looser than the batch test: real time, one seed, short.
"""
import os
import subprocess
import sys
import tempfile
import threading
import time
import unittest
from pathlib import Path

import rospy
import rostest
import yaml

from snake_autonomy.msg import GaitCommand

ROOT = Path(__file__).resolve().parents[2]


class CalibrateRosTest(unittest.TestCase):
    def test_calibration_through_ros_lands_near_the_simulated_robots_and_holds(self):
        rospy.init_node("calibrate_ros_test")
        lock = threading.Lock()
        commands = []

        def on_cmd(msg):
            with lock:
                commands.append((msg.gait, msg.steer, msg.delta))
        rospy.Subscriber("gait_command", GaitCommand, on_cmd, queue_size=100)
        tmp = tempfile.TemporaryDirectory(prefix="calibrate_ros_")
        self.addCleanup(tmp.cleanup)
        out = Path(tmp.name)
        cli = [sys.executable, str(ROOT / "scripts" / "snake_autonomy"), "calibrate", "--ros", "--deltas", "4,10",
               "--settle-cycles", "1", "--cycles", "2", "--start-timeout", "60", "--out", str(out)]
        proc = subprocess.run(cli, capture_output=True, text=True, timeout=120, env=dict(os.environ))
        rospy.loginfo(proc.stdout[-2000:] + proc.stderr[-2000:])
        self.assertEqual(proc.returncode, 0, proc.stderr[-2000:])
        measured = yaml.safe_load((out / "calibration.yaml").read_text())
        configured = yaml.safe_load((ROOT / "config" / "sim.yaml").read_text())["tracker"]
        rospy.loginfo(f"through ROS: {measured['tracker']}; config/sim.yaml: delta0_deg "
                      f"{configured['delta0_deg']}, heading_offset_deg {configured['heading_offset_deg']}")
        self.assertAlmostEqual(measured["tracker"]["delta0_deg"], configured["delta0_deg"], delta=3.0)
        self.assertAlmostEqual(measured["tracker"]["heading_offset_deg"], configured["heading_offset_deg"], delta=5.0)
        self.assertEqual(measured["calibration"]["stopped"], [])
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            with lock:
                if commands and commands[-1][0] == "hold":
                    break
            time.sleep(0.05)
        with lock:
            seen = list(commands)
        self.assertTrue(any(g == "sidewind" and s for g, s, _ in seen), seen[:5])
        self.assertEqual(seen[-1][0], "hold", seen[-5:])


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "calibrate_ros", CalibrateRosTest)
