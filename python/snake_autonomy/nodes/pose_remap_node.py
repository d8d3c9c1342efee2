"""pose_remap_node: RTAB-Map camera odometry -> the driver's base pose (thesis eq. 3.1), with
lost-tracking detection. Wiring only: the logic is estimation.pose_remap.

Subscribes  odom (nav_msgs/Odometry: the camera's pose, e.g. RTAB-Map at 30 Hz), TF.
Publishes   base_pose (geometry_msgs/PoseWithCovarianceStamped, only good poses; the odometry's
            covariance carried over the camera-to-base lever arm, estimation.base_covariance),
            /diagnostics (diagnostic_updater: "pose_remapper: base pose", level OK only while
            tracking, message "STATE: detail", sent on every change of state and every
            ~diagnostic_period s; "pose_remapper: base_pose topic status", the rate of the good poses).
Services    ~reset (std_srvs/Trigger): forget the last pose (after a jump, accept the new track).
Params      ~camera_config (config/camera.yaml: the lost-tracking thresholds; and the extrinsic when
            ~extrinsic is file), ~robot_config (config/robots/cobra.yaml: head length),
            ~world_frame (default: the odometry's frame_id),
            ~extrinsic (tf: the camera's pose in the head from TF, ~head_frame (head_link) ->
            ~camera_frame (camera_link): the URDF's fixed joint, generated from camera.yaml, which stays
            the one file a person edits; poses wait until the transform is known | file: camera.yaml).
Shutdown    a rospy.on_shutdown hook (run before rospy closes the topics) stops the timer and the odom
            callbacks (odometry ignored) and waits for the one under way: nothing is published to a closed topic.
"""
import threading

import diagnostic_updater
import numpy as np
import rospy
import tf2_ros
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from std_srvs.srv import Trigger, TriggerResponse

from snake_autonomy import _core
from snake_autonomy.estimation import (PoseRemapper, TrackingGate, base_covariance, load_camera_calibration,
                                       load_gate_params)
from snake_autonomy.paths import config_path
from snake_autonomy.transforms import matrix_to_pose, pose_to_matrix, rotation_angle

LEVELS = {"ok": DiagnosticStatus.OK, "waiting": DiagnosticStatus.WARN}
STATUS_NAME = "base pose"          # the diagnostic task; /diagnostics names it "<node>: base pose"
EXTRINSIC_MISMATCH_M, EXTRINSIC_MISMATCH_RAD = 1e-3, 1e-3


def transform_to_matrix(t) -> np.ndarray:
    p, q = t.transform.translation, t.transform.rotation
    return pose_to_matrix((p.x, p.y, p.z), (q.x, q.y, q.z, q.w))


class PoseRemapNode:
    def __init__(self):
        self.camera_config = rospy.get_param("~camera_config", str(config_path("camera.yaml")))
        robot_config = rospy.get_param("~robot_config", str(config_path("robots", "cobra.yaml")))
        self.world_frame = rospy.get_param("~world_frame", "")
        self.extrinsic = rospy.get_param("~extrinsic", "tf")
        self.head_frame = rospy.get_param("~head_frame", "head_link")
        self.camera_frame = rospy.get_param("~camera_frame", "camera_link")
        if self.extrinsic not in ("tf", "file"):
            raise ValueError(f"~extrinsic: {self.extrinsic!r} is not tf or file")
        self.calib = load_camera_calibration(self.camera_config)
        if not self.calib.calibrated:
            rospy.logwarn(f"{self.camera_config}: the camera-to-head calibration is marked uncalibrated "
                          f"(calibrated: false): base poses are only as good as its placeholder values")
        self.head_length = _core.RobotModel.from_yaml(robot_config).head_length_m
        self.remapper = None
        self.extrinsic_source = ""
        if self.extrinsic == "file":
            self.use_extrinsic(self.calib.camera_in_head, f"file {self.camera_config}")
        else:
            self.tf_buffer = tf2_ros.Buffer()
            self.tf_listener = tf2_ros.TransformListener(self.tf_buffer)
        self.gate = TrackingGate(load_gate_params(self.camera_config))
        self.last_state = None
        self.lock = threading.Lock()     # one callback at a time; stop() waits for the one under way
        self.stopped = False
        self.pub_pose = rospy.Publisher("base_pose", PoseWithCovarianceStamped, queue_size=10)
        self.updater = diagnostic_updater.Updater()
        self.updater.setHardwareID("rtabmap_odometry")
        self.updater.add(STATUS_NAME, self.diagnose)
        self.pose_freq = diagnostic_updater.HeaderlessTopicDiagnostic(
            "base_pose", self.updater, diagnostic_updater.FrequencyStatusParam({"min": 1.0, "max": 1000.0}, 0.0, 10))
        rospy.Subscriber("odom", Odometry, self.on_odom, queue_size=20)
        rospy.Service("~reset", Trigger, self.srv_reset)
        self.timer = rospy.Timer(rospy.Duration(0.1), self.on_timer)
        rospy.on_shutdown(self.stop)
        self.on_state_change()
        rospy.loginfo(f"pose remapper: H = {self.head_length} m, camera extrinsic from "
                      f"{self.extrinsic_source or f'TF {self.head_frame} -> {self.camera_frame} (waiting)'}")

    def stop(self):
        """No more work in callbacks once the one under way is done: the timer stopped, odometry ignored
        (unregistering would call the master, which may be gone)."""
        with self.lock:
            self.stopped = True
            self.timer.shutdown()

    # -- the extrinsic -------------------------------------------------------------------------------
    def use_extrinsic(self, camera_in_head, source):
        self.remapper = PoseRemapper(camera_in_head, self.head_length)
        self.extrinsic_source = source

    def try_tf_extrinsic(self) -> bool:
        """The camera's pose in the head from TF (robot_state_publisher's /tf_static); True once known."""
        if self.remapper is not None:
            return True
        try:
            t = self.tf_buffer.lookup_transform(self.head_frame, self.camera_frame, rospy.Time(0))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException):
            return False
        T = transform_to_matrix(t)
        self.use_extrinsic(T, f"TF {self.head_frame} -> {self.camera_frame}")
        F = self.calib.camera_in_head
        dp = float(np.linalg.norm(T[:3, 3] - F[:3, 3]))
        da = rotation_angle(F[:3, :3].T @ T[:3, :3])
        if dp > EXTRINSIC_MISMATCH_M or da > EXTRINSIC_MISMATCH_RAD:
            rospy.logwarn(f"the camera extrinsic on TF differs from {self.camera_config} by {dp * 1000:.1f} mm and "
                          f"{np.degrees(da):.2f} deg: robot_description was generated from another calibration "
                          f"(the TF one is used)")
        rospy.loginfo(f"camera extrinsic from {self.extrinsic_source}")
        self.on_state_change()
        return True

    # -- odometry in, base pose out ------------------------------------------------------------------
    def on_odom(self, msg):
        with self.lock:
            if not (self.stopped or rospy.is_shutdown()):
                self.remap(msg)

    def remap(self, msg):
        if not self.try_tf_extrinsic():
            return
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        cov = msg.pose.covariance
        t = msg.header.stamp.to_sec()
        # receive time for both the stale timer and the jump allowance (one clock)
        result = self.gate.check(rospy.get_time(), (p.x, p.y, p.z), (q.x, q.y, q.z, q.w),
                                 [cov[i] for i in (0, 7, 14, 21, 28, 35)])
        if result.ok:
            camera = pose_to_matrix((p.x, p.y, p.z), (q.x, q.y, q.z, q.w))
            (x, y, z), (qx, qy, qz, qw) = matrix_to_pose(self.remapper.base_in_world(camera))
            out = PoseWithCovarianceStamped()
            out.header.stamp = msg.header.stamp if t > 0 else rospy.Time.now()
            out.header.frame_id = self.world_frame or msg.header.frame_id
            out.pose.pose.position.x, out.pose.pose.position.y, out.pose.pose.position.z = x, y, z
            o = out.pose.pose.orientation
            o.x, o.y, o.z, o.w = qx, qy, qz, qw
            out.pose.covariance = base_covariance(cov, camera, self.remapper.base_in_camera).ravel().tolist()
            self.pub_pose.publish(out)
            self.pose_freq.tick()
        if self.gate.state != self.last_state:
            self.on_state_change()

    def on_timer(self, _event):
        with self.lock:
            if not (self.stopped or rospy.is_shutdown()):
                self.check_state()

    def check_state(self):
        """The stale-pose check between odometry messages, and the periodic /diagnostics."""
        self.try_tf_extrinsic()
        self.gate.state_at(rospy.get_time())
        if self.gate.state != self.last_state:
            self.on_state_change()
        self.updater.update()

    def on_state_change(self):
        state, detail = self.gate.state, self.gate.detail
        if state != self.last_state:
            if state == "ok":
                rospy.loginfo(f"base pose: {detail}")
            else:
                rospy.logwarn(f"base pose not forwarded: {state}: {detail}")
        self.last_state = state
        self.updater.force_update()

    def diagnose(self, stat):
        state, detail = self.gate.state, self.gate.detail
        if self.remapper is None:
            state, detail = "waiting", f"no {self.head_frame} -> {self.camera_frame} transform on TF yet"
        stat.summary(LEVELS.get(state, DiagnosticStatus.ERROR), f"{state}: {detail}")
        stat.add("state", state)
        stat.add("accepted", str(self.gate.accepted))
        stat.add("rejected", str(self.gate.rejected))
        stat.add("extrinsic", self.extrinsic_source or "none yet")
        return stat

    def srv_reset(self, _req):
        with self.lock:
            if self.stopped:
                return TriggerResponse(success=False, message="the pose remapper is shutting down")
            self.gate.reset()
            self.on_state_change()
        return TriggerResponse(success=True, message="lost-tracking state reset: the next good pose is accepted")


def main():
    rospy.init_node("pose_remapper")
    try:
        PoseRemapNode()
    except (ValueError, OSError) as exc:
        rospy.logfatal(str(exc))
        return 1
    rospy.spin()
    return 0
