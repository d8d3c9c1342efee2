"""vio_node: visual-inertial odometry of the head camera. Wiring only: the logic is
estimation.vio_stream.VioStream (estimation/vio_fusion.py's VioFusion on live streams).

Subscribes  camera/color/image_raw (rgb8 or bgr8), camera/depth/image_rect_raw (32FC1 m or 16UC1 mm,
            registered to the colour image, same stamps), camera/color/camera_info (the pinhole
            intrinsics: the estimator starts with the first one), camera/imu (sensor_msgs/Imu in the
            IMU's frame, camera_link: the D435i's BMI055, REP 145 units).
Publishes   odom (nav_msgs/Odometry, one per processed frame: header.frame_id ~odom_frame (odom),
            child_frame_id ~camera_frame (camera_link), as rtabmap_ros's odometry: the pose of the IMU's
            camera_link in the odometry frame, which starts level on gravity at the first frame with
            zero yaw; pose covariance the smoother's (geometry_msgs order), 9999 on the diagonal while
            lost; twist: the linear velocity in camera_link, no covariance given),
            /diagnostics ("vio: visual-inertial odometry", every second: frames, tracked, lost,
            failed, dropped, lost intervals and their total, lost frames by cause, smoother restarts,
            first frames waiting for the rest window, the gyro's calibration at rest, ms per frame
            median / p90 / last; WARN while lost, ERROR before the first frame or after a failure in the
            last second). The log says when tracking is lost and why, and when it resumes; and the
            gyro's calibration at rest (a warning with the measured figures when the robot moved).
            No TF: camera_link already hangs from base_link (the URDF), and the pose remapper turns odom
            into base_pose.
Params      ~config (config/estimation.yaml: vo: and fusion:), ~odom_frame, ~camera_frame,
            ~imu_wait_s (0.1: how long a frame waits for the IMU sample at its stamp).
No exception ends the worker: a frame that fails is counted (failed), reported, and published as lost.
Hold the robot still for the fusion's rest window (fusion.rest_calibration_s) after the camera starts:
the gyro's zero-rate offset is measured then, and the first frame waits for it.
"""
import threading

import diagnostic_updater
import numpy as np
import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, Imu

from snake_autonomy.estimation.vio_fusion import load_fusion_params
from snake_autonomy.estimation.vio_stream import VioStream
from snake_autonomy.estimation.visual_odometry import load_vo_params
from snake_autonomy.nodes.image_msgs import from_camera_info, from_image
from snake_autonomy.paths import config_path
from snake_autonomy.perception.camera_model import R_LINK_OPTICAL
from snake_autonomy.transforms import make_transform, matrix_to_quat


def odometry_msg(out, stamp, odom_frame: str, camera_frame: str) -> Odometry:
    m = Odometry()
    m.header.stamp, m.header.frame_id, m.child_frame_id = stamp, odom_frame, camera_frame
    p, q = m.pose.pose.position, m.pose.pose.orientation
    p.x, p.y, p.z = (float(v) for v in out.T_world_link[:3, 3])
    q.x, q.y, q.z, q.w = (float(v) for v in matrix_to_quat(out.T_world_link[:3, :3]))
    m.pose.covariance = [float(v) for v in np.asarray(out.covariance).reshape(36)]
    v = out.T_world_link[:3, :3].T @ out.velocity_m_s
    m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.linear.z = (float(x) for x in v)
    return m


class VioNode:
    def __init__(self):
        path = rospy.get_param("~config", str(config_path("estimation.yaml")))
        self.vo_params, self.fusion_params = load_vo_params(path), load_fusion_params(path)
        self.odom_frame = rospy.get_param("~odom_frame", "odom")
        self.camera_frame = rospy.get_param("~camera_frame", "camera_link")
        self.imu_wait_s = float(rospy.get_param("~imu_wait_s", 0.1))
        self.stream = None                   # made on the first camera_info
        self.bad_inputs, self.failed_seen = 0, 0
        self.was_ok = True
        self.calibration_logged = False
        self._wake = threading.Event()
        self.pub = rospy.Publisher("odom", Odometry, queue_size=20)
        self.updater = diagnostic_updater.Updater()
        self.updater.setHardwareID("head camera")
        self.updater.add("visual-inertial odometry", self.diagnose)
        rospy.Subscriber("camera/color/camera_info", CameraInfo, self.on_info, queue_size=1)
        rospy.Subscriber("camera/imu", Imu, self.on_imu, queue_size=400)
        rospy.Subscriber("camera/color/image_raw", Image, self.on_colour, queue_size=2, buff_size=2 ** 22)
        rospy.Subscriber("camera/depth/image_rect_raw", Image, self.on_depth, queue_size=2, buff_size=2 ** 22)

    # -- callbacks: into the stream ----------------------------------------------------------------------
    def on_info(self, msg):
        if self.stream is not None:
            return
        try:
            K = from_camera_info(msg).K()
        except ValueError as exc:
            self.bad_input(f"camera_info: {exc}")
            return
        self.stream = VioStream(K, make_transform(R_LINK_OPTICAL), self.vo_params, self.fusion_params,
                                self.imu_wait_s)
        rospy.loginfo(f"vio: camera {msg.width}x{msg.height}, fx {K[0, 0]:.1f} px; estimating after "
                      f"{self.fusion_params.rest_calibration_s:g} s at rest (the gyro's calibration)")

    def on_imu(self, msg):
        if self.stream is not None:
            w, a = msg.angular_velocity, msg.linear_acceleration
            self.stream.add_imu(msg.header.stamp.to_sec(), np.array([w.x, w.y, w.z]), np.array([a.x, a.y, a.z]))
            self._wake.set()

    def on_colour(self, msg):
        self._image(msg, "colour")

    def on_depth(self, msg):
        self._image(msg, "depth")

    def _image(self, msg, kind):
        if self.stream is None:
            return
        try:
            a = from_image(msg)
        except ValueError as exc:
            self.bad_input(f"{kind} image: {exc}")
            return
        (self.stream.add_colour if kind == "colour" else self.stream.add_depth)(msg.header.stamp.to_sec(), a)
        self._wake.set()

    def bad_input(self, text):
        self.bad_inputs += 1
        rospy.logwarn_throttle(5.0, f"vio: {text} (ignored; {self.bad_inputs} so far)")

    # -- the worker ----------------------------------------------------------------------------------------
    def spin(self):
        while not rospy.is_shutdown():
            self._wake.wait(0.02)
            self._wake.clear()
            try:
                out = self.stream.step() if self.stream is not None else None
                if out is not None:
                    self.pub.publish(odometry_msg(out, rospy.Time.from_sec(out.stamp), self.odom_frame,
                                                  self.camera_frame))
                    self.log_change(out)
                    self._wake.set()         # another frame may be waiting
                self.updater.update()
            except rospy.ROSException:
                break
            except Exception as exc:         # noqa: BLE001 - the loop outlives any one frame
                self.bad_input(f"worker: {type(exc).__name__}: {exc}")

    def log_change(self, out):
        """The log says when tracking is lost and why, when it resumes, every smoother restart, and the
        gyro's calibration at rest once."""
        calibration = self.stream.fusion.calibration
        if calibration is not None and not self.calibration_logged:
            self.calibration_logged = True
            quiet = calibration.calibrated or self.fusion_params.rest_calibration_s == 0
            (rospy.loginfo if quiet else rospy.logwarn)(f"vio: {calibration.detail}")
        if out.smoother_restarted:
            rospy.logwarn(f"vio: {out.reason}")
        if out.ok != self.was_ok:
            rospy.loginfo(f"vio: tracking at {out.stamp:.2f}" if out.ok
                          else f"vio: lost at {out.stamp:.2f}: {out.reason}")
        self.was_ok = out.ok

    def diagnose(self, stat):
        if self.stream is None:
            stat.summary(DiagnosticStatus.ERROR, "no camera_info yet")
            return stat
        s = self.stream.stats
        values = s.summary()
        values["bad_inputs"] = self.bad_inputs
        if s.frames == 0:
            stat.summary(DiagnosticStatus.ERROR, "no frame yet")
        elif s.failed > self.failed_seen:
            stat.summary(DiagnosticStatus.ERROR, f"{s.failed - self.failed_seen} frame(s) failed: {s.last_error}")
        elif s.lost_now():
            stat.summary(DiagnosticStatus.WARN, f"lost since {s.lost_intervals[-1][0]:.2f}")
        else:
            stat.summary(DiagnosticStatus.OK, "tracking")
        self.failed_seen = s.failed
        for k, v in values.items():
            stat.add(k, f"{v:.3f}" if isinstance(v, float) else str(v))
        return stat


def main():
    rospy.init_node("vio")
    try:
        node = VioNode()
    except (ValueError, OSError) as exc:
        rospy.logfatal(str(exc))
        return 1
    node.spin()
    return 0
