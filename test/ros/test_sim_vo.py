#!/usr/bin/env python3
"""rostest: sim.launch feedback:=vo. The test relays sim_node's head camera (camera/*) to vio_node
(vo_relay/*), drives the rectilinear gait, and checks, over MOVE_S of motion:
- vio_node publishes odom for (nearly) every frame relayed: the camera's rate;
- the pose remapper publishes base_pose from it;
- the estimate of camera_link, aligned to the ground truth at the first frame, stays within
  MAX_ERROR_M of sim_node's ground_truth/camera_pose (same stamps);
then relays blank frames for WITHHELD_S: odom's covariance goes to 9999 (lost) and, once the frames
return, back below the remapper's lost threshold within RECOVER_S."""
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image

from snake_autonomy.msg import GaitCommand
from snake_autonomy.transforms import quat_to_matrix

from driver_test_helpers import wait_for

MOVE_S = 12.0
WITHHELD_S = 2.0
RECOVER_S = 3.0
MAX_ERROR_M = 0.1            # measured on 0.30 m of camera path (the room around the camera, debug visuals
                             # hidden, lit without shadows): 28-77 mm in 17 runs (with the overhead
                             # shadow-casting light the room had before: 27-44 mm in 8 runs, 2 of 11 over
                             # 50 mm); the runaways this guards against went 68-330 mm
LOST = 1000.0                # the pose remapper's lost_covariance


def _T(pose):
    T = np.eye(4)
    T[:3, :3] = quat_to_matrix(pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w)
    T[:3, 3] = (pose.position.x, pose.position.y, pose.position.z)
    return T


class SimVoTest(unittest.TestCase):
    def setUp(self):
        rospy.init_node("sim_vo_test")
        self.lock = threading.Lock()
        self.blank = False
        self.relayed, self.odom, self.base, self.truth = [], [], [], {}
        pubs = {k: rospy.Publisher(f"vo_relay/{k}", t, queue_size=2)
                for k, t in (("color/image_raw", Image), ("depth/image_rect_raw", Image),
                             ("color/camera_info", CameraInfo))}

        def relay(key):
            def on(msg):
                if self.blank and key != "color/camera_info":
                    msg.data = bytes(len(msg.data))        # withheld: a blank image, depth 0
                if key == "color/image_raw":
                    with self.lock:
                        self.relayed.append((time.monotonic(), msg.header.stamp.to_sec()))
                pubs[key].publish(msg)
            return on
        for key, t in (("color/image_raw", Image), ("depth/image_rect_raw", Image), ("color/camera_info", CameraInfo)):
            rospy.Subscriber(f"camera/{key}", t, relay(key), queue_size=2, buff_size=2 ** 22)

        def on_odom(m):
            with self.lock:
                self.odom.append((time.monotonic(), m.header.stamp.to_sec(), _T(m.pose.pose), m.pose.covariance[0],
                                  m.header.frame_id, m.child_frame_id))

        def on_truth(m):
            with self.lock:
                self.truth[round(m.header.stamp.to_sec(), 6)] = _T(m.pose)
        rospy.Subscriber("odom", Odometry, on_odom, queue_size=50)
        rospy.Subscriber("base_pose", PoseWithCovarianceStamped,
                         lambda m: self.base.append(time.monotonic()), queue_size=50)
        rospy.Subscriber("ground_truth/camera_pose", PoseStamped, on_truth, queue_size=50)
        self.gait = rospy.Publisher("gait_command", GaitCommand, queue_size=10)

    def drive(self, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.gait.publish(GaitCommand(gait="rectilinear"))
            time.sleep(0.5)

    def test_vo_feedback(self):
        wait_for(lambda: any(o[3] < LOST for o in self.odom), 80, "a first tracked odom")
        wait_for(lambda: self.gait.get_num_connections() > 0, 10, "the driver to subscribe gait_command")
        t0 = time.monotonic()
        self.drive(MOVE_S)
        t1 = time.monotonic()
        self.blank = True
        self.drive(WITHHELD_S)
        t2 = time.monotonic()
        self.blank = False
        self.drive(RECOVER_S + 1.0)
        with self.lock:
            odom, relayed, base, truth = list(self.odom), list(self.relayed), list(self.base), dict(self.truth)
        moving = [o for o in odom if t0 <= o[0] < t1]
        frames = [r for r in relayed if t0 <= r[0] < t1 - 0.2]
        print(f"moving {t1 - t0:.1f} s: {len(frames)} frames relayed ({len(frames) / (t1 - t0):.2f} Hz), "
              f"{len(moving)} odom, {sum(1 for b in base if t0 <= b < t1)} base_pose", flush=True)
        self.assertEqual((moving[-1][4], moving[-1][5]), ("odom", "camera_link"))
        self.assertGreaterEqual(len(moving), 0.9 * len(frames), "odom for (nearly) every relayed frame")
        self.assertGreater(len(frames) / (t1 - t0), 5.0, "the camera's rate (10 Hz asked)")
        self.assertTrue(all(o[3] < LOST for o in moving), "tracked while moving")
        self.assertGreaterEqual(sum(1 for b in base if t0 <= b < t1), 0.9 * len(moving), "base_pose from odom")
        # the estimate against the ground truth, aligned at the first frame that has both
        pairs = [(o[2], truth[round(o[1], 6)]) for o in odom if o[0] < t1 and round(o[1], 6) in truth]
        self.assertGreater(len(pairs), 0.8 * len([o for o in odom if o[0] < t1]), "ground truth for the frames")
        align = pairs[0][1] @ np.linalg.inv(pairs[0][0])
        err = [float(np.linalg.norm((align @ e)[:3, 3] - g[:3, 3])) for e, g in pairs]
        path = sum(float(np.linalg.norm(b[1][:3, 3] - a[1][:3, 3])) for a, b in zip(pairs, pairs[1:]))
        print(f"{len(pairs)} frames, camera path {path:.3f} m: error max {max(err) * 1000:.1f} mm, "
              f"mean {np.mean(err) * 1000:.1f} mm, last {err[-1] * 1000:.1f} mm", flush=True)
        self.assertGreater(path, 0.05, "the head moved")
        self.assertLess(max(err), MAX_ERROR_M)
        # withheld, then back
        withheld = [o for o in odom if t1 + 0.5 <= o[0] < t2]
        self.assertTrue(withheld and all(o[3] >= 9999.0 for o in withheld), [o[3] for o in withheld])
        back = [o[0] - t2 for o in odom if o[0] >= t2 and o[3] < LOST]
        print(f"withheld: {len(withheld)} lost odom; tracked again {back[0] if back else None} s after", flush=True)
        self.assertTrue(back and back[0] < RECOVER_S, "tracking back after the frames return")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_vo", SimVoTest)
