#!/usr/bin/env python3
"""rostest: the tracker's and the follower's gains changed at run time with dynamic_reconfigure's client.

The Servers start from the configuration files; a new tracker gain changes the steering of the running
mission at its next tick (delta = delta0 + clamp(kp psi_e, +-delta_lim): with delta_lim 0 the command's
delta is delta0); a value beyond the cfg's range is clamped, a NaN is refused and changes nothing; a new
follower gain reaches the running loop's follower (the planner's diagnostics read it there).
"""
import math
import os
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from dynamic_reconfigure.client import Client
from sensor_msgs.msg import CameraInfo
from std_srvs.srv import Trigger

from snake_autonomy.missions import load_defaults
from snake_autonomy.nodes.image_msgs import to_camera_info
from snake_autonomy.paths import config_path
from snake_autonomy.perception.camera_model import CameraIntrinsics
from snake_autonomy.planning.rectilinear.config import NavConfig
from snake_autonomy.srv import LoadMission

from mission_test_helpers import FakeDriver, wait_for

MISSION = "name: far\nwaypoints:\n  - [20.0, 0.0, 0.0]\ntime_limit_s: 120\n"   # 40 s of sidewinding away


class GainTuningTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("gain_tuning_test")
        cls.diagnostics = {}   # status name -> latest DiagnosticStatus
        rospy.Subscriber("/diagnostics", DiagnosticArray,
                         lambda msg: cls.diagnostics.update({st.name: st for st in msg.status}))
        cls.driver = FakeDriver()
        cls.tracker = Client("/mission/tracker", timeout=30)
        cls.follower = Client("/planner/follower", timeout=30)
        rospy.wait_for_service("mission/load", 20)
        cls.load = rospy.ServiceProxy("mission/load", LoadMission)
        cls.start = rospy.ServiceProxy("mission/start", Trigger)
        cls.abort = rospy.ServiceProxy("mission/abort", Trigger)

    def diag_values(self, name):
        st = self.diagnostics.get(name)
        return {kv.key: kv.value for kv in st.values} if st is not None else {}

    def wait_diag(self, name, key, value, what):
        wait_for(lambda: self.diag_values(name).get(key) == value, 10, what)

    def test_1_the_servers_start_from_the_configuration_files(self):
        tracker = load_defaults(None)["tracker"]
        config = self.tracker.get_configuration(timeout=10)
        self.assertAlmostEqual(config["kp"], tracker["kp"])
        self.assertAlmostEqual(config["delta0_deg"], math.degrees(tracker["delta0"]))
        self.assertAlmostEqual(config["delta_lim_deg"], math.degrees(tracker["delta_lim"]))
        follower = NavConfig.from_yaml(str(config_path("nav.yaml"))).follower
        config = self.follower.get_configuration(timeout=10)
        for key in ("k_heading", "lookahead_m", "kappa_rate_per_m_s"):
            self.assertAlmostEqual(config[key], getattr(follower, key))
        self.wait_diag("mission: tracker gains", "changes", "0", "the tracker gains' diagnostics")

    def test_2_a_tracker_gain_changes_the_running_missions_steering(self):
        path = os.path.join(os.environ.get("ROS_HOME", "/tmp"), "gain_tuning_far.yaml")
        with open(path, "w") as f:
            f.write(MISSION)
        self.assertTrue(self.load(path).success)
        self.assertTrue(self.start().success)
        try:
            wait_for(lambda: any(c.gait == "sidewind" for c in self.driver.commands), 10, "the first sidewind")
            config = self.tracker.update_configuration({"delta0_deg": 10.0, "delta_lim_deg": 0.0})
            self.assertEqual((config["delta0_deg"], config["delta_lim_deg"]), (10.0, 0.0))
            n = len(self.driver.commands)      # one tick may have been under way: judge the ones after it
            later = lambda: [c for c in self.driver.commands[n + 1:] if c.gait == "sidewind"]  # noqa: E731
            wait_for(lambda: len(later()) >= 3, 10, "three sidewind commands after the change")
            for c in later():                    # delta0 alone: the proportional term's limit is 0 now
                self.assertAlmostEqual(c.delta, math.radians(10.0), places=6)
            self.wait_diag("mission: tracker gains", "delta0_deg", "10", "the tracker's delta0 in use")
            self.assertEqual(self.diag_values("mission: tracker gains")["delta_lim_deg"], "0")
        finally:
            self.abort()

    def test_3_a_tracker_gain_beyond_its_range_is_clamped_and_nan_refused(self):
        config = self.tracker.update_configuration({"kp": 50.0})
        self.assertEqual(config["kp"], 10.0)                         # Tracker.cfg's max
        self.wait_diag("mission: tracker gains", "kp", "10", "kp 10 in use")
        config = self.tracker.update_configuration({"kp": float("nan"), "delta0_deg": 5.0})
        self.assertEqual((config["kp"], config["delta0_deg"]), (10.0, 10.0))   # refused whole
        self.wait_diag("mission: tracker gains", "refused", "1", "the refusal counted")
        values = self.diag_values("mission: tracker gains")
        self.assertIn("kp: must be a finite number, got nan", values["last_refusal"])
        self.assertEqual((values["kp"], values["delta0_deg"]), ("10", "10"))

    def test_4_a_follower_gain_reaches_the_running_loops_follower(self):
        pub = rospy.Publisher("camera/color/camera_info", CameraInfo, queue_size=1, latch=True)
        pub.publish(to_camera_info(CameraIntrinsics.d435i_like(), rospy.Time.now(), "camera_color_optical_frame"))
        wait_for(lambda: "planner: navigation" in self.diagnostics
                 and self.diagnostics["planner: navigation"].message != "waiting for camera_info", 20,
                 "the planner's loop (camera_info taken)")
        config = self.follower.update_configuration({"k_heading": 0.05})
        self.assertAlmostEqual(config["k_heading"], 0.05)
        self.wait_diag("planner: follower gains", "k_heading", "0.05", "k_heading 0.05 in the loop's follower")
        config = self.follower.update_configuration({"lookahead_m": float("nan")})
        self.assertAlmostEqual(config["lookahead_m"], 0.15)
        self.wait_diag("planner: follower gains", "refused", "1", "the follower's refusal counted")
        self.assertEqual(self.diag_values("planner: follower gains")["lookahead_m"], "0.15")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "gain_tuning", GainTuningTest)
