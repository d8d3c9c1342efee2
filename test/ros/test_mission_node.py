#!/usr/bin/env python3
"""rostest: mission_node against a fake driver publishing com_pose.

The fake driver integrates a kinematic CoM at 50 Hz: sidewind moves 0.5 m/s along the yaw, turns
rotate at 30 deg/s, hold stops. Checks: a bad mission is refused with every problem listed; a good
one runs to the end, holds and writes its results; a stale pose holds and resumes; abort holds; a
driver fault aborts the mission (and the driver's recovery does not restart it).
These start missions through the services (mission/load, mission/start, mission/abort); the action
(mission/run) has its own test, test_mission_action.py.
"""
import glob
import json
import math
import os
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from std_srvs.srv import Trigger

from snake_autonomy.msg import TrackingStatus
from snake_autonomy.srv import LoadMission

from mission_test_helpers import FakeDriver, wait_for


class MissionNodeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("mission_node_test")
        cls.statuses = []
        rospy.Subscriber("tracking_status", TrackingStatus, cls.statuses.append)
        cls.diagnostics = {}   # status name -> latest DiagnosticStatus
        rospy.Subscriber("/diagnostics", DiagnosticArray,
                         lambda msg: cls.diagnostics.update({st.name: st for st in msg.status}))
        cls.driver = FakeDriver()
        for s in ("mission/load", "mission/start", "mission/abort"):
            rospy.wait_for_service(s, 20)
        cls.load = rospy.ServiceProxy("mission/load", LoadMission)
        cls.start = rospy.ServiceProxy("mission/start", Trigger)
        cls.abort = rospy.ServiceProxy("mission/abort", Trigger)

    def test_1_bad_mission_is_refused_with_every_problem(self):
        path = os.path.join(os.environ.get("ROS_HOME", "/tmp"), "bad_mission.yaml")
        with open(path, "w") as f:
            f.write("waypoints:\n  - [0, 0]\n  - [1, .nan, 0]\ngaits: {sidewind: slither}\n")
        r = self.load(path)
        self.assertFalse(r.success)
        for text in ("3 problem(s)", "waypoints[0]: expected [x_m, y_m, heading_deg]", "waypoints[1][1] (y_m)",
                     "gaits.sidewind: unknown gait 'slither'"):
            self.assertIn(text, r.message)
        self.assertFalse(self.start().success)         # nothing loaded: nothing moves
        self.assertEqual(self.driver.gait, "hold")

    def test_2_mission_runs_to_the_end_and_writes_results(self):
        r = self.load(rospy.get_param("~mission_file"))
        self.assertTrue(r.success, r.message)
        results = rospy.get_param("~results_dir")
        before = set(glob.glob(os.path.join(results, "*_straight")))
        n0 = len(self.statuses)
        self.assertTrue(self.start().success)
        wait_for(lambda: any(s.done for s in self.statuses[n0:]), 30, "the mission to finish")
        run = self.statuses[n0:]
        reached = [s.waypoint_index - 1 for s in run if s.waypoint_reached]
        self.assertEqual(reached, [0, 1])
        self.assertTrue(all(s.mode == 1 and s.gait in ("sidewind", "hold") for s in run))
        self.assertEqual(run[-1].gait, "hold")
        wait_for(lambda: self.driver.commands and self.driver.commands[-1].gait == "hold", 5, "a hold command")
        steering = [c for c in self.driver.commands if c.gait == "sidewind"]
        self.assertTrue(steering and all(c.steer for c in steering))
        self.assertAlmostEqual(steering[0].delta, math.radians(14.0), places=3)
        new = lambda: sorted(set(glob.glob(os.path.join(results, "*_straight"))) - before)  # noqa: E731
        wait_for(lambda: len(new()) == 1, 10, "this run's results folder")
        run_dir = new()[0]
        # the figure written last: the results folder is complete
        wait_for(lambda: os.path.isfile(os.path.join(run_dir, "yaw_error_vs_distance.png")), 30, "the figures")
        metrics = json.load(open(os.path.join(run_dir, "metrics.json")))
        self.assertTrue(metrics["outcome"].startswith("done"))
        self.assertEqual([w["reached"] for w in metrics["waypoints"]], [True, True])
        self.assertLessEqual(metrics["waypoints"][1]["final_distance_m"], 0.35)
        self.assertTrue(os.path.isfile(os.path.join(run_dir, "run.bag")))
        # diagnostic_updater: the mission's state and the tracker's rate on /diagnostics
        name = next((n for n in self.diagnostics if n.endswith(": mission")), None)
        self.assertIsNotNone(name, sorted(self.diagnostics))
        wait_for(lambda: self.diagnostics[name].message.startswith("done"), 5, "the mission diagnostics to say done")
        values = {kv.key: kv.value for kv in self.diagnostics[name].values}
        self.assertEqual(values["mission"], "straight")
        self.assertTrue(any(n.endswith("tracking_status topic status") for n in self.diagnostics),
                        sorted(self.diagnostics))

    def test_3_stale_pose_holds_then_resumes_and_abort_holds(self):
        with self.driver.lock:
            self.driver.x, self.driver.y, self.driver.yaw = -3.0, 0.0, 0.0   # far from the first waypoint
        self.assertTrue(self.load(rospy.get_param("~mission_file")).success)
        n0 = len(self.statuses)
        self.assertTrue(self.start().success)
        wait_for(lambda: any(s.gait == "sidewind" for s in self.statuses[n0:]), 10, "sidewinding")
        with self.driver.lock:
            self.driver.publishing = False
        n1 = len(self.statuses)
        wait_for(lambda: any(s.pose_stale for s in self.statuses[n1:]), 5, "a stale status")
        stale = next(s for s in self.statuses[n1:] if s.pose_stale)
        self.assertEqual(stale.gait, "hold")
        self.assertIn("s old", stale.note)
        self.assertTrue(math.isnan(stale.distance))
        wait_for(lambda: self.driver.gait == "hold", 5, "the driver to be told to hold")
        with self.driver.lock:
            self.driver.publishing = True
        n2 = len(self.statuses)
        wait_for(lambda: any(not s.pose_stale and s.gait == "sidewind" for s in self.statuses[n2:]), 10,
                 "tracking to resume")
        r = self.abort()
        self.assertTrue(r.success and "operator" in r.message)
        wait_for(lambda: self.driver.gait == "hold", 5, "hold after abort")
        n3 = len(self.statuses)
        time_limit = time.monotonic() + 1.0
        while time.monotonic() < time_limit:   # no more decisions after the abort
            time.sleep(0.05)
        self.assertEqual(len(self.statuses), n3)

    def test_4_a_driver_fault_aborts_and_the_recovery_does_not_move(self):
        with self.driver.lock:
            self.driver.x, self.driver.y, self.driver.yaw = -3.0, 0.0, 0.0
        self.assertTrue(self.load(rospy.get_param("~mission_file")).success)
        n0 = len(self.statuses)
        self.assertTrue(self.start().success)
        wait_for(lambda: any(s.gait == "sidewind" for s in self.statuses[n0:]), 10, "sidewinding")
        self.driver.publish_locomotion(2, "fault: bus: the port closed (I/O error)")
        wait_for(lambda: self.driver.gait == "hold", 3, "hold after the driver's fault")
        mission = wait_for(lambda: self.diagnostics.get("mission: mission") if "driver fault" in getattr(
            self.diagnostics.get("mission: mission"), "message", "") else None, 5, "the mission's diagnostics")
        self.assertEqual(mission.level, 2)
        self.assertIn("aborted: driver fault: bus: the port closed", mission.message)
        r = self.start()
        self.assertFalse(r.success)
        self.assertIn("the driver reports a fault", r.message)
        with self.driver.lock:
            n1 = len(self.driver.commands)
        self.driver.publish_locomotion(0, "holding")      # torque re-enabled: the driver holds, recovered
        time.sleep(2.0)                                    # no tick may send the robot off again
        with self.driver.lock:
            after = [c.gait for c in self.driver.commands[n1:]]
        self.assertTrue(all(g == "hold" for g in after), after)
        self.assertEqual(self.driver.gait, "hold")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "mission_node_fake_driver", MissionNodeTest)
