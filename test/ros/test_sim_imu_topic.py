#!/usr/bin/env python3
"""rostest: sim_node publishes the head camera's IMU on camera/imu (sensor_msgs/Imu) at about
sim.yaml's imu.rate_hz, in camera_link, with REP 145's units: at rest the accelerometer reads
+9.81 m/s^2 along camera_link's z (the camera lies level) and the gyro its zero-rate offset (the one
the seed draws: launch seed 0); no orientation
(orientation_covariance[0] = -1) and the white noise's variances on the diagonals."""
import threading
import unittest

import numpy as np
import rospy
import rostest
from sensor_msgs.msg import Imu

from snake_autonomy.paths import config_path
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.imu import ImuSensor

from driver_test_helpers import wait_for

WINDOW_S = 4.0


class SimImuTopicTest(unittest.TestCase):
    def test_camera_imu_reads_gravity_at_rest_at_its_rate(self):
        rospy.init_node("sim_imu_test")
        sim = SimConfig.from_yaml(config_path("sim.yaml"))
        cfg = sim.imu
        offset = ImuSensor(cfg, sim.draw(0).rng("imu")).gyro_offset_rad_s      # sim_imu.test's seed
        lock, msgs = threading.Lock(), []

        def on_imu(msg):
            with lock:
                msgs.append((rospy.get_time(), msg))

        rospy.Subscriber("camera/imu", Imu, on_imu, queue_size=500)
        wait_for(lambda: len(msgs) > 0, 90, "a first camera/imu message")
        rospy.sleep(2.0)                          # dropped from 1 mm at the start: settled
        with lock:
            start = len(msgs)
        rospy.sleep(WINDOW_S)
        with lock:
            window = msgs[start:]
        stamps = np.array([m.header.stamp.to_sec() for _, m in window])
        rate = (len(stamps) - 1) / (stamps[-1] - stamps[0])
        self.assertGreater(rate, 0.8 * cfg.rate_hz, "camera/imu rate (Hz, by the stamps)")
        self.assertLess(rate, 1.05 * cfg.rate_hz)
        m = window[-1][1]
        self.assertEqual(m.header.frame_id, "camera_link")
        self.assertEqual(m.orientation_covariance[0], -1.0)
        self.assertAlmostEqual(m.angular_velocity_covariance[0], cfg.gyro_std_rad_s ** 2)
        self.assertAlmostEqual(m.linear_acceleration_covariance[8], cfg.accel_std_m_s2 ** 2)
        accel = np.array([[x.linear_acceleration.x, x.linear_acceleration.y, x.linear_acceleration.z]
                          for _, x in window]).mean(axis=0)
        gyro = np.array([[x.angular_velocity.x, x.angular_velocity.y, x.angular_velocity.z]
                         for _, x in window]).mean(axis=0)
        np.testing.assert_allclose(accel, [0.0, 0.0, 9.81], atol=0.05)
        self.assertGreater(np.abs(offset).max(), 0.002, "the seed's gyro offset (the test needs one)")
        self.assertLess(np.abs(gyro - offset).max(), 0.002, f"mean gyro at rest {gyro} rad/s, offset {offset}")


if __name__ == "__main__":
    rostest.rosrun("snake_autonomy", "sim_imu", SimImuTopicTest)
