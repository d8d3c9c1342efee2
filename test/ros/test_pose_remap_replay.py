#!/usr/bin/env python3
"""rostest: odometry replayed into pose_remap_node; base_pose is eq. 3.1 with the camera extrinsic read
from TF (robot_state_publisher's head_link -> camera_link, generated from camera.yaml), carries the
odometry's covariance moved to the base, bad poses never pass; the status is on /diagnostics."""
import math
import threading
import time
import unittest

import rospy
import rostest
import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from std_srvs.srv import Trigger

from driver_test_helpers import wait_for

H = 0.1565
STATUS = "pose_remapper: base pose"
YAW = math.radians(30)


def odom(x, y, yaw=YAW, cov=0.01, qw=None):
    m = Odometry()
    m.header.stamp = rospy.Time.now()
    m.header.frame_id = "odom"
    m.child_frame_id = "camera_link"
    m.pose.pose.position.x, m.pose.pose.position.y = x, y
    q = m.pose.pose.orientation
    q.z, q.w = math.sin(yaw / 2), math.cos(yaw / 2)
    if qw is not None:
        q.z, q.w = 0.0, qw
    m.pose.covariance = [cov if i in (0, 7, 14, 21, 28, 35) else 0.0 for i in range(36)]
    return m


class PoseRemapReplay(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("pose_remap_replay")
        cls.lock = threading.Lock()
        cls.poses, cls.states = [], []
        rospy.Subscriber("base_pose", PoseWithCovarianceStamped, lambda m: cls._add(cls.poses, m))
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diagnostics)
        cls.pub = rospy.Publisher("odom", Odometry, queue_size=50)
        wait_for(lambda: cls.pub.get_num_connections() > 0, 15, "the remapper to subscribe to odom")
        wait_for(lambda: cls.states, 15, "a first status on /diagnostics")

    @classmethod
    def on_diagnostics(cls, msg):
        for s in msg.status:
            if s.name == STATUS:
                cls._add(cls.states, s)

    @classmethod
    def _add(cls, store, m):
        with cls.lock:
            store.append(m)

    def last_state(self):
        with self.lock:
            return self.states[-1].message.split(":")[0] if self.states else ""

    def send(self, msgs, rate=30.0):
        for m in msgs:
            m.header.stamp = rospy.Time.now()
            self.pub.publish(m)
            time.sleep(1.0 / rate)

    def test_replay(self):
        self.assertEqual(self.last_state(), "waiting")
        # the extrinsic comes from TF once robot_state_publisher's /tf_static arrived
        wait_for(lambda: self.states and {kv.key: kv.value for kv in self.states[-1].values}.get("extrinsic", "")
                 .startswith("TF head_link -> camera_link"), 15, "the extrinsic from TF")
        # 1. a good track: camera moving along its heading (30 deg), level
        track = [odom(0.01 * i * math.cos(YAW), 0.01 * i * math.sin(YAW)) for i in range(15)]
        self.send(track)
        wait_for(lambda: len(self.poses) >= 15, 10, "15 base poses")
        last_cov = np.asarray(self.poses[-1].pose.covariance).reshape(6, 6)
        last = self.poses[-1].pose
        cx, cy = 0.14 * math.cos(YAW), 0.14 * math.sin(YAW)
        # eq. 3.1 with the level-camera calibration: the base is H ahead of the camera, same heading
        self.assertAlmostEqual(last.pose.position.x, cx + H * math.cos(YAW), places=6)
        self.assertAlmostEqual(last.pose.position.y, cy + H * math.sin(YAW), places=6)
        q = last.pose.orientation
        self.assertAlmostEqual(2 * math.atan2(q.z, q.w), YAW, places=6)
        self.assertEqual(self.poses[-1].header.frame_id, "odom")
        # covariance: 0.01 on the diagonal, moved over the lever arm H along the heading (level camera):
        # the yaw variance adds H^2 x 0.01 across the heading, nothing along it
        across = np.array([-math.sin(YAW), math.cos(YAW), 0.0])
        along = np.array([math.cos(YAW), math.sin(YAW), 0.0])
        self.assertAlmostEqual(float(across @ last_cov[:3, :3] @ across), 0.01 + H * H * 0.01, places=9)
        self.assertAlmostEqual(float(along @ last_cov[:3, :3] @ along), 0.01, places=9)
        self.assertAlmostEqual(last_cov[5, 5], 0.01, places=12)
        wait_for(lambda: self.last_state() == "ok", 5, "status ok")

        # 2. NaN, RTAB-Map's null pose (covariance 9999), a zero quaternion, a 2 m jump: none forwarded
        for bad, state in ((odom(float("nan"), 0.0), "invalid"), (odom(0.0, 0.0, cov=9999.0, qw=1.0), "lost"),
                           (odom(0.14, 0.0, qw=0.0), "lost"), (odom(2.0, 2.0), "jump")):
            n = len(self.poses)
            self.send([bad])
            wait_for(lambda s=state: self.last_state() == s, 5, f"status {state}")
            self.send([odom(2.0 + 0.01, 2.0)] if state == "jump" else [])
            time.sleep(0.0)
            self.assertEqual(len(self.poses), n, f"a {state} pose was forwarded")
            if state != "jump":
                self.send([odom(cx, cy)])            # back on the track: accepted again
                wait_for(lambda m=n: len(self.poses) == m + 1, 5, f"the pose after {state}")
                wait_for(lambda: self.last_state() == "ok", 5, "status ok again")
        # 3. after the jump the new track is refused until ~reset
        n = len(self.poses)
        self.send([odom(2.0 + 0.01 * i, 2.0) for i in range(5)])
        self.assertEqual(len(self.poses), n)
        rospy.wait_for_service("pose_remapper/reset", 5)
        self.assertTrue(rospy.ServiceProxy("pose_remapper/reset", Trigger)().success)
        self.send([odom(2.06, 2.0)])
        wait_for(lambda: len(self.poses) == n + 1, 5, "a pose after reset")
        # 4. silence: stale within the timeout (0.5 s) plus the 10 Hz check
        wait_for(lambda: self.last_state() == "stale", 3, "status stale")
        for p in self.poses:
            p = p.pose
            self.assertTrue(all(math.isfinite(v) for v in (p.pose.position.x, p.pose.position.y, p.pose.position.z)))
        levels = {s.message.split(":")[0]: s.level for s in self.states}
        self.assertEqual(levels["ok"], DiagnosticStatus.OK)
        for s in ("invalid", "lost", "jump", "stale"):
            self.assertEqual(levels[s], DiagnosticStatus.ERROR)


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "pose_remap_replay", PoseRemapReplay)
