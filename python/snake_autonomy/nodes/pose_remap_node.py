"""pose_remap_node: RTAB-Map camera odometry -> the driver's base pose (thesis eq. 3.1), with
lost-tracking detection. Wiring only: the logic is estimation.pose_remap.

Subscribes  odom (nav_msgs/Odometry: the camera's pose, e.g. RTAB-Map at 30 Hz).
Publishes   base_pose (geometry_msgs/PoseStamped, only good poses), base_pose_status
            (diagnostic_msgs/DiagnosticStatus, latched; on every change and at 1 Hz; level OK only
            while tracking), /diagnostics.
Services    ~reset (std_srvs/Trigger): forget the last pose (after a jump, accept the new track).
Params      ~camera_config (config/camera.yaml), ~robot_config (config/robots/cobra.yaml: head length),
            ~world_frame (default: the odometry's frame_id).
"""

import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from std_srvs.srv import Trigger, TriggerResponse

from snake_autonomy.estimation import (PoseRemapper, TrackingGate, load_camera_calibration,
                                       load_gate_params)
from snake_autonomy.paths import config_path
from snake_autonomy.transforms import matrix_to_pose, pose_to_matrix

LEVELS = {"ok": DiagnosticStatus.OK, "waiting": DiagnosticStatus.WARN}


class PoseRemapNode:
    def __init__(self):
        camera_config = rospy.get_param("~camera_config", str(config_path("camera.yaml")))
        robot_config = rospy.get_param("~robot_config", str(config_path("robots", "cobra.yaml")))
        self.world_frame = rospy.get_param("~world_frame", "")
        calib = load_camera_calibration(camera_config)
        if not calib.calibrated:
            rospy.logwarn(f"{camera_config}: the camera-to-head calibration is marked uncalibrated "
                          f"(calibrated: false): base poses are only as good as its placeholder values")
        from snake_autonomy import _core
        head_length = _core.RobotModel.from_yaml(robot_config).head_length_m
        self.remapper = PoseRemapper(calib.camera_in_head, head_length)
        self.gate = TrackingGate(load_gate_params(camera_config))
        self.last_state = None
        self.pub_pose = rospy.Publisher("base_pose", PoseStamped, queue_size=10)
        self.pub_status = rospy.Publisher("base_pose_status", DiagnosticStatus, queue_size=5, latch=True)
        self.pub_diag = rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=5)
        rospy.Subscriber("odom", Odometry, self.on_odom, queue_size=20)
        rospy.Service("~reset", Trigger, self.srv_reset)
        rospy.Timer(rospy.Duration(0.1), self.on_timer)
        self._last_diag = 0.0
        self.publish_status()
        rospy.loginfo(f"pose remapper: H = {head_length} m, calibration from {camera_config}")

    def on_odom(self, msg):
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        cov = msg.pose.covariance
        t = msg.header.stamp.to_sec()
        # receive time for both the stale timer and the jump allowance (one clock)
        result = self.gate.check(rospy.get_time(), (p.x, p.y, p.z), (q.x, q.y, q.z, q.w),
                                 [cov[i] for i in (0, 7, 14, 21, 28, 35)])
        if result.ok:
            T = self.remapper.base_in_world(pose_to_matrix((p.x, p.y, p.z), (q.x, q.y, q.z, q.w)))
            (x, y, z), (qx, qy, qz, qw) = matrix_to_pose(T)
            out = PoseStamped()
            out.header.stamp = msg.header.stamp if t > 0 else rospy.Time.now()
            out.header.frame_id = self.world_frame or msg.header.frame_id
            out.pose.position.x, out.pose.position.y, out.pose.position.z = x, y, z
            o = out.pose.orientation
            o.x, o.y, o.z, o.w = qx, qy, qz, qw
            self.pub_pose.publish(out)
        if self.gate.state != self.last_state:
            self.publish_status()

    def on_timer(self, _event):
        self.gate.state_at(rospy.get_time())
        now = rospy.get_time()
        if self.gate.state != self.last_state or now - self._last_diag >= 1.0:
            self.publish_status()

    def publish_status(self):
        state, detail = self.gate.state, self.gate.detail
        if state != self.last_state:
            if state == "ok":
                rospy.loginfo(f"base pose: {detail}")
            else:
                rospy.logwarn(f"base pose not forwarded: {state}: {detail}")
        self.last_state = state
        self._last_diag = rospy.get_time()
        status = DiagnosticStatus(level=LEVELS.get(state, DiagnosticStatus.ERROR), name="pose_remapper",
                                  message=f"{state}: {detail}", hardware_id="rtabmap_odometry",
                                  values=[KeyValue("state", state), KeyValue("accepted", str(self.gate.accepted)),
                                          KeyValue("rejected", str(self.gate.rejected))])
        self.pub_status.publish(status)
        arr = DiagnosticArray(status=[status])
        arr.header.stamp = rospy.Time.now()
        self.pub_diag.publish(arr)

    def srv_reset(self, _req):
        self.gate.reset()
        self.publish_status()
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
