"""The visual-inertial fusion's heading (estimation/vio_fusion.py): a calibrated gyro against a
camera whose rotations drift. The head yaws back and forth as sidewinding turns it (25 deg at
0.5 Hz) over a fixed point, the IMU is sim/imu.py's BMI055-like model on the true readings (its
bias starting at zero, as a gyro calibrated beforehand's, or at a BMI055-like zero-rate offset the
fusion calibrates at rest: the robot still for REST_S before the first frame), and the visual
odometry is replaced by a stub that
measures every motion from a keyframe taken every third frame, its rotation turning 0.2 deg/s too
fast about the vertical: the error a chain of keyframes adds up. The heading is unobservable from
gravity; what the fusion makes of the gyro's bias decides whether it follows the gyro or the camera.
"""
import math

import numpy as np

from snake_autonomy.estimation.vio_fusion import FusionParams, VioFusion
from snake_autonomy.estimation.visual_odometry import OK, VoResult
from snake_autonomy.perception.camera_model import R_LINK_OPTICAL
from snake_autonomy.sim.imu import ImuConfig, ImuSensor
from snake_autonomy.transforms import make_transform, rot_z

FRAME_S, IMU_S = 0.1, 0.005
T_IMU_CAMERA = make_transform(R_LINK_OPTICAL)
AMPLITUDE_RAD, FREQUENCY_HZ = math.radians(25.0), 0.5
DRIFT_RAD_S = math.radians(0.2)                 # the camera's rotations run this much too fast
K = np.array([[307.5, 0.0, 160.0], [0.0, 307.5, 120.0], [0.0, 0.0, 1.0]])


def yaw(t):
    return AMPLITUDE_RAD * math.sin(2 * math.pi * FREQUENCY_HZ * t)


def yaw_rate(t):
    return AMPLITUDE_RAD * 2 * math.pi * FREQUENCY_HZ * math.cos(2 * math.pi * FREQUENCY_HZ * t)


def T_world_imu(t):
    return make_transform(rot_z(yaw(t)), np.array([0.0, 0.0, 0.05]))


class DriftingCamera:
    """Stands in for VisualOdometry: tracked poses in its own frame, the keyframe every third frame,
    the heading running DRIFT_RAD_S fast; the PnP covariance 2 mm and 0.1 deg."""

    def __init__(self):
        self.pose, self.keyframe = np.eye(4), None

    def reset(self, T_odom_camera=None, covariance=None):
        self.keyframe = None

    def camera(self, t):
        return make_transform(rot_z(DRIFT_RAD_S * t)) @ T_world_imu(t) @ T_IMU_CAMERA

    def process(self, image, depth_m, stamp, mask=None, predicted=None):
        T = self.camera(stamp)
        cov = np.diag([0.002 ** 2] * 3 + [math.radians(0.1) ** 2] * 3)
        if self.keyframe is None or int(round(stamp / FRAME_S)) % 3 == 0:
            self.keyframe = (stamp, T)
            self.pose = T
            return VoResult(stamp, T, cov, OK, inliers=100, keyframe=True, relative_covariance=np.zeros((6, 6)))
        self.pose = T
        return VoResult(stamp, T, cov, OK, inliers=100, relative_covariance=cov, keyframe_stamp=self.keyframe[0],
                        T_odom_keyframe=self.keyframe[1])


def fused_heading_errors_deg(params, seconds=40.0, imu_config=None, rest_s=0.0):
    """The fused heading's error against the truth at every frame, and the camera's own; the IMU
    (imu_config, default: no offset) still for rest_s before the first frame (t = 0)."""
    imu = ImuSensor(imu_config or ImuConfig(gyro_offset_deg_s=0.0), np.random.default_rng(3))
    vio = VioFusion(K, T_IMU_CAMERA, params=params, initial_imu_pose=T_world_imu(0.0))
    vio.vo = DriftingCamera()
    blank = np.zeros((240, 320), np.uint8), np.zeros((240, 320), np.float32)
    n_imu, fused, camera = -int(round(rest_s / IMU_S)), [], []
    for i in range(int(seconds / FRAME_S) + 1):
        t = FRAME_S * i
        while n_imu * IMU_S <= t + 1e-9:
            rate = yaw_rate(n_imu * IMU_S) if n_imu > 0 else 0.0     # still up to the first frame
            s = imu.measure(n_imu * IMU_S, np.array([0.0, 0.0, rate]), np.array([0.0, 0.0, 9.80665]))
            vio.add_imu(s.t_s, s.angular_velocity_rad_s, s.linear_acceleration_m_s2)
            n_imu += 1
        r = vio.add_frame(*blank, t)
        assert r.ok or i == 0, r.reason
        R = r.T_world_imu[:3, :3]
        fused.append(math.degrees(math.atan2(R[1, 0], R[0, 0])) - math.degrees(yaw(t)))
        camera.append(math.degrees(DRIFT_RAD_S * t))
    return np.array(fused), np.array(camera)


def test_the_fused_heading_follows_a_calibrated_gyro_not_the_cameras_drift():
    """With the gyro bias known to be small (prior_gyro_bias_sigma_rad_s 1e-4, a gyro calibrated
    beforehand: no rest window, no offset) the heading stays with the gyro while the camera's drifts
    8 deg in 40 s; with the former loose prior (5e-3 rad/s, 0.29 deg/s) the bias takes the camera's
    drift and the heading follows it."""
    tight, camera = fused_heading_errors_deg(FusionParams(rest_calibration_s=0.0))
    loose, _ = fused_heading_errors_deg(FusionParams(rest_calibration_s=0.0, prior_gyro_bias_sigma_rad_s=5e-3))
    assert camera[-1] > 7.9
    assert np.abs(tight).max() < 1.5, np.abs(tight).max()
    assert abs(loose[-1]) > 3.0, loose[-1]


def test_a_gyro_with_a_zero_rate_offset_calibrated_at_rest_keeps_the_heading_uncalibrated_it_drifts():
    """The gyro with a BMI055-like zero-rate offset (0.5 deg/s std per axis, drawn), the robot still
    for 2 s before the first frame: calibrated there (the shipped fusion), the heading stays within
    1.5 deg of the truth; the tight prior centred on zero instead (rest_calibration_s 0, as if the
    gyro were calibrated) holds the bias at zero, and the heading drifts with the offset."""
    imu = ImuConfig(gyro_offset_deg_s=0.5)
    offset_deg_s = math.degrees(ImuSensor(imu, np.random.default_rng(3)).gyro_offset_rad_s[2])
    assert abs(offset_deg_s) > 0.15                     # about the vertical: what the heading integrates
    calibrated, _ = fused_heading_errors_deg(FusionParams(), imu_config=imu, rest_s=2.0)
    shortcut, _ = fused_heading_errors_deg(FusionParams(rest_calibration_s=0.0), imu_config=imu, rest_s=2.0)
    assert np.abs(calibrated).max() < 1.5, np.abs(calibrated).max()
    assert np.abs(shortcut).max() > 3.0, np.abs(shortcut).max()
