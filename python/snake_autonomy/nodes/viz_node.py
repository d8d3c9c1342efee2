"""viz_node: rviz helpers. Wiring only (markers built in viz_markers).

Subscribes  com_pose (PoseStamped), bound_state (snake_autonomy/BoundState), tracking_status,
            mission/waypoints (PoseArray, latched by the mission node).
Publishes   viz/markers (visualization_msgs/MarkerArray: waypoints, the active one with its d_th
            circle, the bounding box), viz/path (nav_msgs/Path: the CoM path travelled),
            /diagnostics (diagnostic_updater, every ~diagnostic_period s, default 1: "snake_viz: inputs"
            says which inputs arrived, "viz/markers topic status" the marker rate against ~rate_hz).
Params      ~d_th (0.35 m), ~path_min_step_m (0.01), ~path_max_poses (20000), ~rate_hz (5).
"""
import math

import diagnostic_updater
import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseArray, PoseStamped
from nav_msgs.msg import Path
from visualization_msgs.msg import MarkerArray

from snake_autonomy.msg import BoundState, TrackingStatus
from snake_autonomy.nodes.viz_markers import bounding_box_marker, waypoint_markers


class VizNode:
    def __init__(self):
        self.d_th = float(rospy.get_param("~d_th", 0.35))
        self.min_step = float(rospy.get_param("~path_min_step_m", 0.01))
        self.max_poses = int(rospy.get_param("~path_max_poses", 20000))
        self.waypoints, self.frame, self.active = [], "odom", 0
        self.bound = None
        self.com_count = 0
        self.path = Path()
        self.pub_markers = rospy.Publisher("viz/markers", MarkerArray, queue_size=2)
        self.pub_path = rospy.Publisher("viz/path", Path, queue_size=2)
        rospy.Subscriber("mission/waypoints", PoseArray, self.on_waypoints, queue_size=1)
        rospy.Subscriber("tracking_status", TrackingStatus, self.on_status, queue_size=5)
        rospy.Subscriber("com_pose", PoseStamped, self.on_com, queue_size=20)
        rospy.Subscriber("bound_state", BoundState, self.on_bound, queue_size=5)
        rate_hz = float(rospy.get_param("~rate_hz", 5.0))
        self.updater = diagnostic_updater.Updater()
        self.updater.setHardwareID("none")
        self.updater.add("inputs", self.diagnose_inputs)
        bounds = {"min": rate_hz, "max": rate_hz}
        self.markers_diag = diagnostic_updater.HeaderlessTopicDiagnostic(
            "viz/markers", self.updater, diagnostic_updater.FrequencyStatusParam(bounds, 0.2, 5))
        rospy.Timer(rospy.Duration(1.0 / rate_hz), self.on_timer)

    def on_waypoints(self, msg):
        self.frame = msg.header.frame_id or self.frame
        self.waypoints = [(p.position.x, p.position.y, 2 * math.atan2(p.orientation.z, p.orientation.w))
                          for p in msg.poses]
        self.active = 0
        self.path.poses = []

    def on_status(self, msg):
        self.active = msg.waypoint_index

    def on_bound(self, msg):
        self.bound = msg

    def on_com(self, msg):
        self.com_count += 1
        p = msg.pose.position
        if not all(math.isfinite(v) for v in (p.x, p.y, p.z)):
            return
        self.path.header.frame_id = msg.header.frame_id or self.frame
        if self.path.poses:
            q = self.path.poses[-1].pose.position
            if math.hypot(p.x - q.x, p.y - q.y) < self.min_step:
                return
        self.path.poses.append(msg)
        if len(self.path.poses) > self.max_poses:
            del self.path.poses[: len(self.path.poses) - self.max_poses]

    def on_timer(self, _event):
        if rospy.is_shutdown():
            return
        try:
            self.draw()
        except rospy.ROSException as exc:     # shutting down between the check and a publish
            if not rospy.is_shutdown():
                rospy.logerr_throttle(5.0, f"viz: {exc}")

    def draw(self):
        stamp = rospy.Time.now()
        markers = waypoint_markers(self.frame, stamp, self.waypoints, self.active, self.d_th)
        if self.bound is not None:
            markers.append(bounding_box_marker(self.bound.header.frame_id or self.frame, stamp,
                                               self.bound.com_pose, self.bound.span))
        self.pub_markers.publish(MarkerArray(markers=markers))
        self.path.header.stamp = stamp
        self.pub_path.publish(self.path)
        self.markers_diag.tick()
        self.updater.update()

    def diagnose_inputs(self, stat):
        """OK once com_pose arrived; waypoints and the bounding box are optional (no mission, no driver)."""
        if self.com_count:
            stat.summary(DiagnosticStatus.OK, f"drawing {len(self.waypoints)} waypoint(s) and the path")
        else:
            stat.summary(DiagnosticStatus.WARN, "no com_pose received yet: no path to draw")
        stat.add("frame", self.frame)
        stat.add("waypoints", str(len(self.waypoints)))
        stat.add("active waypoint", str(self.active))
        stat.add("com_pose messages", str(self.com_count))
        stat.add("path poses", str(len(self.path.poses)))
        stat.add("bound_state received", str(self.bound is not None))
        return stat


def main():
    rospy.init_node("snake_viz")
    VizNode()
    rospy.spin()
    return 0
