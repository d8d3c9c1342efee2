#!/usr/bin/env python3
"""rostest: the three systems in one mission through ROS (config/missions/three_systems.yaml in
config/worlds/three_systems.yaml): the waypoint tracker sidewinds to its waypoint, planner_node crawls
with the rectilinear gait past two cylinders to the navigate_to leg's goal, the scout stop raises the
head there (FBSR plan, the driver's trajectory execution).

Checks: the mission ends done with both waypoints reached (metrics.json); the leg went to planner_node
as one move_base goal that SUCCEEDED, and the planner drove it with the rectilinear gait; the scout stop
is on the leg's waypoint, done, its phases in order, held hold_s; while raised the head (TF world frame
-> base_link) rose to the planned 0.3 m within 3 cm (sim_scout's tolerance) and was down again at the
end, and metrics.json's measured_head_height_m (base_pose's z while held) is within 3 cm of the plan;
the simulated robot touched no cylinder and never rolled over (sim_node's diagnostics).
"""
import glob
import json
import os
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray
from move_base_msgs.msg import MoveBaseActionResult
from snake_autonomy.msg import GaitCommand
from std_msgs.msg import String

from mission_test_helpers import wait_for

MISSION_S = 240.0        # measured 93-95 s of mission (sidewind 3 s, the leg 61 s, the scout stop 20 s)
PLANNED_M = 0.3
HOLD_S = 3.0
HEAD_TOL_M = 0.03


def sim_values(msg):
    """sim_node's values from a /diagnostics message ("... simulated robot"), or None."""
    ours = [st for st in msg.status if st.name.endswith("simulated robot")]
    return {kv.key: kv.value for kv in ours[0].values} if ours else None


class SimThreeSystemsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_three_systems_test")
        cls.lock = threading.Lock()
        cls.kept = {"state": [""], "commands": [], "results": [], "sim": [{}]}
        cls.started_wall = time.time()
        rospy.Subscriber("mission/state", String, lambda m: cls.keep("state", m.data), queue_size=5)
        rospy.Subscriber("gait_command", GaitCommand,
                         lambda m: cls.keep("commands", (m._connection_header["callerid"], m.gait)), queue_size=50)
        rospy.Subscriber("move_base/result", MoveBaseActionResult, lambda m: cls.keep("results", m), queue_size=5)
        rospy.Subscriber("/diagnostics", DiagnosticArray, lambda m: cls.keep("sim", sim_values(m)), queue_size=20)
        cls.tf = tf2_ros.Buffer(rospy.Duration(30.0))
        cls.listener = tf2_ros.TransformListener(cls.tf)

    @classmethod
    def keep(cls, key, value):
        if value is not None:
            with cls.lock:
                cls.kept[key].append(value)

    @property
    def state(self):
        return self.kept["state"][-1]

    def head_z(self):
        world = rospy.get_param("/driver/world_frame", "map")
        try:
            t = self.tf.lookup_transform(world, "base_link", rospy.Time(0), rospy.Duration(0.2))
        except (tf2_ros.LookupException, tf2_ros.ExtrapolationException, tf2_ros.ConnectivityException):
            return None
        return t.transform.translation.z

    def this_run(self):
        runs = [d for d in glob.glob(os.path.join(rospy.get_param("~results_dir"), "*_three_systems"))
                if os.path.getmtime(d) >= self.started_wall - 5]
        return sorted(runs, key=os.path.getmtime)[-1] if runs else None

    def test_sidewind_then_crawl_past_the_cylinders_then_raise_the_head(self):
        wait_for(lambda: self.state.startswith("running"), 90, "the mission running")
        t0, heads = time.monotonic(), []
        while self.state.startswith("running") and time.monotonic() - t0 < MISSION_S:
            z = self.head_z()
            if z is not None:
                heads.append(z)
            time.sleep(0.1)
        rospy.loginfo(f"sim_three_systems: mission ran {time.monotonic() - t0:.0f} s: {self.state}")
        self.assertTrue(self.state.startswith("done"), self.state)

        wait_for(lambda: self.this_run() and os.path.isfile(os.path.join(self.this_run(), "yaw_errors.png")),
                 60, "the run's results")
        metrics = json.load(open(os.path.join(self.this_run(), "metrics.json")))
        rospy.loginfo("sim_three_systems: waypoints reached at " + ", ".join(
            f"{w['time_to_reach_s']:.1f} s" for w in metrics["waypoints"] if w["reached"]))
        self.assertTrue(metrics["all_reached"], metrics["waypoints"])
        self.assertEqual([w["reached"] for w in metrics["waypoints"]], [True, True])

        with self.lock:
            results, sim = list(self.kept["results"]), dict(self.kept["sim"][-1])
            planner_gaits = [g for who, g in self.kept["commands"] if who == "/planner"]
        self.assertEqual(len(results), 1, "one move_base result: the navigate_to leg")
        self.assertEqual(results[0].status.status, results[0].status.SUCCEEDED, results[0].status.text)
        self.assertGreaterEqual(planner_gaits.count("rectilinear"), 5, "the planner crawled")

        scouts = metrics.get("scouts", [])
        self.assertEqual(len(scouts), 1, metrics.get("scouts"))
        stop = scouts[0]
        self.assertEqual((stop["waypoint_index"], stop["outcome"]), (1, "done"), stop)
        phases = stop["phases"]
        self.assertEqual(list(phases), ["planning", "raising", "holding", "lowering", "done"])
        self.assertGreaterEqual(phases["lowering"] - phases["holding"], HOLD_S - 1e-6)
        self.assertAlmostEqual(stop["planned_head_height_m"], PLANNED_M, delta=0.01)
        self.assertTrue(heads, "no world -> base_link transform seen")
        top = max(heads)
        rospy.loginfo(f"sim_three_systems: head highest {top:.3f} m (planned {stop['planned_head_height_m']:.3f} "
                      f"m), last {heads[-1]:.3f} m; sim_node {sim}")
        self.assertLess(abs(top - stop["planned_head_height_m"]), HEAD_TOL_M)
        self.assertLess(heads[-1], 0.1, "the head was not lowered")
        # metrics.json's measured height: the lowest base_pose z while held, as the batch run reports it
        self.assertIsNotNone(stop["measured_head_height_m"], stop)
        self.assertLess(abs(stop["measured_head_height_m"] - stop["planned_head_height_m"]), HEAD_TOL_M, stop)

        self.assertEqual(sim.get("rolled_over"), "False", f"sim_node: {sim}")
        self.assertEqual(sim.get("obstacle_contacts"), "0", f"sim_node: {sim}")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_three_systems", SimThreeSystemsTest)
