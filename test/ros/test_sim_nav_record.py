#!/usr/bin/env python3
"""rostest: sim.launch robot:=chang_rectilinear world:=test/ros/worlds/nav_record.yaml (record on).

Checks: the 12-link robot runs through ROS (its 11 joints on /joint_states, its URDF as
robot_description); nav_record_node ends the record once the robot rests in the goal's disc and
leaves a results folder: a bag with /tf, /tf_static, /diagnostics, the camera at a low rate and the
navigation topics; metrics.json with the navigation runs' contract (runs/nav_metrics.py, as
`snake_autonomy nav run` writes it), the goal reached; the batch run's files (topview.png,
trajectory.csv, ...); `snake_autonomy report DIR` rebuilds the same metrics from the bag.
"""
import json
import math
import tempfile
import threading
import unittest
from pathlib import Path

import rosbag
import rospy
import rostest
from sensor_msgs.msg import JointState

from driver_test_helpers import wait_for

ROBOT = "chang_rectilinear"
RECORD_TIMEOUT_S = 170.0     # MuJoCo's model (up to 60 s on a loaded machine), ~10 s of gait, 3 s at rest
FILES = ("run.bag", "metrics.json", "trajectory.csv", "commands.csv", "contacts.csv", "replans.csv", "topview.png")
TOPICS = ("/tf", "/tf_static", "/diagnostics", "/camera/color/image_raw", "/camera/color/camera_info",
          "/gait_command", "/base_pose", "/ground_truth/base_pose", "/joint_states", "/nav/path", "/nav/arcs",
          "/nav/traversability", "/sim/world_markers", "/snake_autonomy/run")
CAMERA_PERIOD_S = 2.0        # the test's record_camera_period_s (sim_node renders at 0.5 Hz)


class SimNavRecordTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_nav_record_test")
        cls.results = Path(rospy.get_param("~results_dir"))
        cls.world_file = rospy.get_param("~world")
        cls.lock = threading.Lock()
        cls.joint_states = None
        rospy.Subscriber("joint_states", JointState, cls.on_joints, queue_size=5)

    @classmethod
    def on_joints(cls, msg):
        with cls.lock:
            cls.joint_states = msg

    def test_the_12_link_robot_is_simulated_and_its_run_recorded(self):
        from snake_autonomy import _core
        from snake_autonomy.paths import robot_yaml
        model = _core.RobotModel.from_yaml(str(robot_yaml(ROBOT)))
        js = wait_for(lambda: self.joint_states, 120.0, "/joint_states")
        self.assertEqual(len(js.name), model.num_joints)
        self.assertEqual(len(js.position), model.num_joints)
        self.assertIn(f'<robot name="{ROBOT}">', rospy.get_param("/robot_description"))

        run_dir = wait_for(lambda: self.finished_run(), RECORD_TIMEOUT_S, "the record's metrics.json")
        # topview.png is the last file written
        wait_for(lambda: (run_dir / "topview.png").is_file(), 30.0, f"{run_dir}/topview.png")
        for name in FILES:
            self.assertTrue((run_dir / name).is_file(), f"{run_dir}: no {name}")
        m = json.loads((run_dir / "metrics.json").read_text())
        print({k: m[k] for k in ("goal_reached", "end", "time_s", "final_distance_m", "collisions", "replans")})

        with rosbag.Bag(str(run_dir / "run.bag")) as bag:
            info = bag.get_type_and_topic_info().topics
            duration = bag.get_end_time() - bag.get_start_time()
        for topic in TOPICS:
            self.assertIn(topic, info, f"{topic} not in the bag ({sorted(info)})")
        # the camera at the record's low rate, not sim_node's 0.5 Hz... nor every frame of a faster one
        self.assertLessEqual(info["/camera/color/image_raw"].message_count, duration / CAMERA_PERIOD_S + 2)

        # the contract every navigation run's metrics.json keeps (runs/nav_metrics.py, what `nav run`
        # writes besides its batch-only figures): the keys of an empty run's metrics
        import numpy as np
        from snake_autonomy.runs.nav_metrics import NavFacts, nav_metrics
        from snake_autonomy.sim.world_file import load_world
        contract = nav_metrics(NavFacts(
            world=load_world(self.world_file), trajectory=np.zeros((0, 3)), t_end_s=0.0, final_pose=(0.0, 0.0, 0.0),
            loop_reached_t_s=None, stop_xy=None, collisions=0, min_clearance_m=math.nan, path_length_m=0.0,
            replans=[], stops_no_free_arc=0, rolled_over=False, contact_modes=[], min_radius_m=1.0, identity={}))
        self.assertEqual(sorted(set(contract) - set(m)), [])
        self.assertEqual(m["robot"], ROBOT)
        self.assertEqual(m["world"], self.world_file)
        # the short world is reached: the loop stopped in the disc and base_link rests inside it
        self.assertEqual(m["end"], "goal_reached")
        self.assertTrue(m["goal_reached"] and m["loop_reached"], m)
        self.assertLess(m["final_distance_m"], 0.15)
        self.assertEqual(m["outcome"], "success")
        self.assertGreaterEqual(m["replans"], 1)
        self.assertTrue(math.isfinite(m["path_length_m"]) and m["path_length_m"] > 0.05, m["path_length_m"])

        from snake_autonomy.cli import main as cli_main
        with tempfile.TemporaryDirectory() as tmp:
            self.assertEqual(cli_main(["report", str(run_dir), "--out", tmp]), 0)
            again = json.loads((Path(tmp) / "metrics.json").read_text())
            self.assertEqual(again, m)
            self.assertGreater((Path(tmp) / "topview.png").stat().st_size, 0)

    def finished_run(self):
        """The run's folder once metrics.json is there (the recorder writes it when the record ends)."""
        done = sorted(self.results.glob("*_nav_*/metrics.json"))
        return done[0].parent if done else None


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_nav_record", SimNavRecordTest)
