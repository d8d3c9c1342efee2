#!/usr/bin/env python3
"""rostest: planner_node survives bad inputs and keeps commanding (planner_inputs.test).

The test is the robot's other nodes: it publishes camera_info, base_pose and depth frames of a flat
floor seen by COBRA's head camera, and feeds the planner what a faulty driver, camera or estimator
sends: a first camera_info with fx = 0, a NaN pose, a depth image of another size than camera_info,
an unknown encoding, too few bytes, a camera that falls silent. After each, the planner must still
send a gait command every tick (no gap longer than GAP_S), name the refusal on /diagnostics, hold on
a stale frame, and move again (rectilinear, curve=true) once good data returns.
"""
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from sensor_msgs.msg import CameraInfo, Image, JointState
from snake_autonomy.msg import GaitCommand
from snake_autonomy.nodes.image_msgs import to_camera_info, to_image

from driver_test_helpers import wait_for

GAP_S = 2.0              # the planner commands at 2 Hz: a gap this long means its loop stopped
FRAME_TIMEOUT_S = 2.0    # as planner_inputs.test gives ~frame_timeout_s
STOPS = ("hold", "hold_curve")   # the straight hold before camera_info, the stop keeping kappa after


def floor_depth(k, T_ground_optical):
    """Depth (m) of a flat floor z = 0 seen by a camera at T_ground_optical; 0 where no floor."""
    v, u = np.mgrid[0:k.height, 0:k.width]
    rays = np.dstack([(u - k.cx) / k.fx, (v - k.cy) / k.fy, np.ones(u.shape)])
    down = rays @ T_ground_optical[:3, :3].T                       # the rays in the ground frame
    z = np.where(down[..., 2] < -1e-6, -T_ground_optical[2, 3] / np.minimum(down[..., 2], -1e-6), 0.0)
    return np.where(z < 4.0, z, 0.0).astype(np.float32)


class PlannerInputsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("planner_inputs_test")
        from snake_autonomy import _core
        from snake_autonomy.paths import config_path
        from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera
        cfg = NavConfig.from_yaml()
        cls.k = cfg.intrinsics
        cls.radius = _core.RobotModel.from_yaml(str(config_path("robots", "cobra.yaml"))).link_radius_m
        cls.depth = floor_depth(cls.k, T_ground_camera(cfg.mount, cls.radius))
        cls.lock = threading.Lock()
        cls.commands, cls.planner = [], {}
        cls.pub_info = rospy.Publisher("camera/color/camera_info", CameraInfo, queue_size=2)
        cls.pub_depth = rospy.Publisher("camera/depth/image_rect_raw", Image, queue_size=2)
        cls.pub_pose = rospy.Publisher("base_pose", PoseWithCovarianceStamped, queue_size=5)
        cls.pub_joints = rospy.Publisher("joint_states", JointState, queue_size=5)
        rospy.Subscriber("gait_command", GaitCommand, cls.on_cmd, queue_size=50)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diagnostics, queue_size=20)
        cls.poses_on, cls.frames_on, cls.nan_poses = False, False, 0
        cls.timer = rospy.Timer(rospy.Duration(0.05), cls.stream)

    @classmethod
    def tearDownClass(cls):
        # Stopped before rospy closes the publishers, so no publish() to a closed topic at exit.
        cls.poses_on = cls.frames_on = False
        cls.timer.shutdown()

    @classmethod
    def stream(cls, _event):
        """Poses at 20 Hz and depth frames at 4 Hz while switched on."""
        if rospy.is_shutdown():
            return
        now = rospy.Time.now()
        if cls.poses_on:
            m = PoseWithCovarianceStamped()
            m.header.stamp, m.header.frame_id = now, "map"
            m.pose.pose.position.z = cls.radius
            m.pose.pose.orientation.w = 1.0
            if cls.nan_poses > 0:
                cls.nan_poses -= 1
                m.pose.pose.position.x = float("nan")
            cls.pub_pose.publish(m)
        if cls.frames_on and now.to_nsec() // 50_000_000 % 5 == 0:
            cls.pub_depth.publish(to_image(cls.depth, "32FC1", now, "camera_depth_optical_frame"))

    @classmethod
    def on_cmd(cls, msg):
        with cls.lock:
            cls.commands.append((rospy.get_time(), msg.gait, msg.curve))

    @classmethod
    def on_diagnostics(cls, msg):
        for st in msg.status:
            if st.name.endswith("navigation"):
                with cls.lock:
                    cls.planner = dict({kv.key: kv.value for kv in st.values}, summary=st.message, level=st.level)

    def until(self, cond, timeout_s, what):
        """Waits for cond; a failure names what and the planner's diagnostics at the time."""
        try:
            wait_for(cond, timeout_s, what)
        except AssertionError as exc:
            with self.lock:
                raise AssertionError(f"{exc}; planner diagnostics: {self.planner}") from None

    def refused_after(self, frame, key, count):
        """Publishes frame every 0.3 s until the planner's diagnostics count key >= count."""
        def sent_and_counted():
            self.pub_depth.publish(frame)
            time.sleep(0.3)
            return int(self.diag(key)) >= count
        self.until(sent_and_counted, 15.0, f"{key} >= {count}")

    def diag(self, key, default="0"):
        with self.lock:
            return self.planner.get(key, default)

    def moving(self, since):
        with self.lock:
            return any(t >= since and gait not in STOPS and curve for t, gait, curve in self.commands)

    def holding_since(self, since):
        with self.lock:
            after = [g for t, g, _ in self.commands if t >= since]
        return len(after) >= 2 and all(g in STOPS for g in after)

    def assert_never_silent(self):
        with self.lock:
            times = [t for t, _, _ in self.commands]
        self.assertGreater(len(times), 2)
        gaps = np.diff(times)
        self.assertLess(gaps.max(), GAP_S, f"the planner sent no command for {gaps.max():.1f} s")

    def info(self, fx):
        k = self.k
        from snake_autonomy.perception.camera_model import CameraIntrinsics
        return to_camera_info(CameraIntrinsics(k.width, k.height, fx, k.fy, k.cx, k.cy), rospy.Time.now(),
                                   "camera_color_optical_frame")

    def test_bad_inputs_are_dropped_counted_and_the_planner_commands_on(self):
        self.until(lambda: self.pub_info.get_num_connections() > 0, 20.0, "planner not up")
        self.until(lambda: len(self.commands) > 0, 20.0, "no gait command from the planner")
        # a camera_info with fx = 0 first: refused, the loop not built on it
        self.pub_info.publish(self.info(0.0))
        self.until(lambda: int(self.diag("refused_camera_info")) >= 1, 10.0, "a refused camera_info")
        self.assertIn("fx", self.diag("last_refusal", ""))
        # good data: the planner moves
        self.pub_info.publish(self.info(self.k.fx))
        type(self).poses_on = type(self).frames_on = True
        t0 = rospy.get_time()
        self.until(lambda: self.moving(t0), 30.0, "moving on a free floor")
        # a NaN pose: refused, counted
        type(self).nan_poses = 3
        self.until(lambda: int(self.diag("refused_pose")) >= 3, 10.0, "3 refused poses")
        # joint_states naming too few joints: refused, named, counted (the body sweep keeps the last good ones)
        joints = JointState(name=[f"joint_{i}" for i in range(1, 11)], position=[0.0] * 10)

        def sent_and_counted():
            joints.header.stamp = rospy.Time.now()
            self.pub_joints.publish(joints)
            time.sleep(0.3)
            return int(self.diag("refused_joints")) >= 1
        self.until(sent_and_counted, 15.0, "a refused joint_states")
        self.assertIn("joint_11", self.diag("last_refusal", ""))
        # frames the planner cannot use: another size than camera_info, an unknown encoding, too few bytes.
        # Each is sent until its refusal is counted: the depth subscriber keeps only the newest frame, so
        # one of the stream's good frames may replace it before the planner reads it
        now = rospy.Time.now()
        self.refused_after(to_image(np.ones((100, 100), np.float32), "32FC1", now, "cam"), "refused_frame", 1)
        bad = to_image(self.depth, "32FC1", now, "cam")
        bad.encoding = "64FC3"
        self.refused_after(bad, "refused_depth", 1)
        short = to_image(self.depth, "32FC1", now, "cam")
        short.data = short.data[:1000]
        self.refused_after(short, "refused_depth", 2)
        t1 = rospy.get_time()
        self.until(lambda: self.moving(t1), 10.0, "moving after the bad frames")
        # the camera falls silent: hold within frame_timeout_s (+ a tick), stale on /diagnostics
        type(self).frames_on = False
        t2 = rospy.get_time()
        self.until(lambda: self.diag("state", "") == "stale", FRAME_TIMEOUT_S + 5.0, "state stale")
        t_stale = rospy.get_time()
        self.until(lambda: self.holding_since(t_stale), 5.0, "holding on a stale frame")
        self.assertLess(t_stale - t2, FRAME_TIMEOUT_S + 3.0)
        # frames again: moving again
        type(self).frames_on = True
        t3 = rospy.get_time()
        self.until(lambda: self.moving(t3), 15.0, "moving again")
        self.assertEqual(self.diag("tick_errors"), "0")
        self.assertEqual(self.diag("node_errors"), "0")
        self.assert_never_silent()


    def test_map_and_traversability_mask_show_a_wall_ahead(self):
        """nav/map (OccupancyGrid in the pose's frame: the default layered planner's local map, local_map.cell_m
        cells, occupied / free / unknown) marks cells near a wall the depth frames show 0.5 m ahead, and only
        there; nav/traversability_mask is mono8 of the camera's size, 0 on the wall."""
        from nav_msgs.msg import OccupancyGrid
        from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera
        cfg = NavConfig.from_yaml()
        T = T_ground_camera(cfg.mount, self.radius)
        k = self.k
        v, u = np.mgrid[0:k.height, 0:k.width]
        rays = np.dstack([(u - k.cx) / k.fx, (v - k.cy) / k.fy, np.ones(u.shape)]) @ T[:3, :3].T
        ahead = rays[..., 0] > 1e-6
        t_wall = np.where(ahead, (0.5 - T[0, 3]) / np.where(ahead, rays[..., 0], 1.0), np.inf)  # x = 0.5 m
        on_wall = ahead & (T[2, 3] + t_wall * rays[..., 2] >= 0.0) & (T[2, 3] + t_wall * rays[..., 2] <= 0.3)
        floor = np.where(self.depth > 0, self.depth, np.inf)
        wall = np.where(on_wall & (t_wall < floor), t_wall, self.depth).astype(np.float32)
        got = {}
        subs = [rospy.Subscriber(topic, msg_type, lambda m, topic=topic: got.__setitem__(topic, m), queue_size=1)
                for topic, msg_type in (("nav/map", OccupancyGrid), ("nav/traversability_mask", Image))]
        flat = self.depth
        try:
            type(self).depth = wall
            self.pub_info.publish(self.info(self.k.fx))
            type(self).poses_on = type(self).frames_on = True

            def occupied():
                m = got.get("nav/map")
                return m is not None and 100 in m.data
            self.until(occupied, 30.0, "nav/map with an occupied cell (a replan of the wall)")
        finally:
            type(self).depth = flat
            for sub in subs:
                sub.unregister()
        m = got["nav/map"]
        self.assertEqual(m.header.frame_id, "map")
        self.assertAlmostEqual(m.info.resolution, cfg.local_map.cell_m, places=6)
        self.assertEqual(len(m.data), m.info.width * m.info.height)
        grid = np.array(m.data, np.int8).reshape(m.info.height, m.info.width)
        self.assertTrue(set(np.unique(grid)) <= {-1, 0, 100} and 0 in grid, np.unique(grid))
        j, i = np.nonzero(grid == 100)
        x = m.info.origin.position.x + (i + 0.5) * m.info.resolution
        self.assertTrue(np.all((x > 0.2) & (x < 1.0)), f"occupied cells at x {x.min():.2f}..{x.max():.2f} m")
        mask = got["nav/traversability_mask"]
        self.assertEqual((mask.encoding, mask.width, mask.height), ("mono8", k.width, k.height))
        self.assertEqual(mask.header.frame_id, "camera_color_optical_frame")
        img = np.frombuffer(mask.data, np.uint8).reshape(k.height, k.width)
        self.assertTrue(set(np.unique(img)) <= {0, 255})
        self.assertTrue(np.any(img[on_wall] == 0) and np.any(img[-1] == 255), "the wall not ground, the floor ground")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "planner_inputs", PlannerInputsTest)
