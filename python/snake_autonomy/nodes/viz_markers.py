"""rviz markers of the mission (waypoints, the active one, the d_th circle) and of the robot's
bounding box. Pure message builders: no node, no master."""
import math

from geometry_msgs.msg import Point, Pose, Vector3
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker

GREY = ColorRGBA(0.6, 0.6, 0.6, 0.9)
ACTIVE = ColorRGBA(1.0, 0.55, 0.0, 1.0)
DONE = ColorRGBA(0.2, 0.8, 0.2, 0.9)
BOX = ColorRGBA(0.2, 0.5, 1.0, 0.25)


def _marker(frame, stamp, ns, mid, mtype):
    m = Marker()
    m.header.frame_id, m.header.stamp = frame, stamp
    m.ns, m.id, m.type, m.action = ns, mid, mtype, Marker.ADD
    m.pose.orientation.w = 1.0
    return m


def waypoint_markers(frame, stamp, waypoints, active_index, d_th):
    """Arrows (heading) + labels for every waypoint; reached ones green, the active one orange with
    its d_th circle."""
    out = []
    for i, (x, y, h) in enumerate(waypoints):
        colour = DONE if i < active_index else ACTIVE if i == active_index else GREY
        a = _marker(frame, stamp, "waypoints", i, Marker.ARROW)
        a.pose = Pose()
        a.pose.position.x, a.pose.position.y = x, y
        a.pose.orientation.z, a.pose.orientation.w = math.sin(h / 2), math.cos(h / 2)
        a.scale = Vector3(0.3, 0.04, 0.04)
        a.color = colour
        out.append(a)
        label = _marker(frame, stamp, "waypoint_labels", i, Marker.TEXT_VIEW_FACING)
        label.pose.position.x, label.pose.position.y, label.pose.position.z = x, y, 0.15
        label.scale.z = 0.12
        label.color = colour
        label.text = f"WP{i}"
        out.append(label)
    ring = _marker(frame, stamp, "active_waypoint", 0, Marker.LINE_STRIP)
    if 0 <= active_index < len(waypoints):
        x, y, _ = waypoints[active_index]
        ring.scale.x = 0.02
        ring.color = ACTIVE
        ring.points = [Point(x + d_th * math.cos(a), y + d_th * math.sin(a), 0.0)
                       for a in (2 * math.pi * k / 48 for k in range(49))]
    else:
        ring.action = Marker.DELETE
    out.append(ring)
    return out


def bounding_box_marker(frame, stamp, com_pose, span):
    """The bounding box of BoundState: a cube at the CoM with the virtual chassis' orientation."""
    m = _marker(frame, stamp, "bounding_box", 0, Marker.CUBE)
    m.pose = com_pose
    m.scale = Vector3(span.x, span.y, span.z)
    m.color = BOX
    return m
