"""Synthetic inputs for the evaluation tests: a 30 s run at 10 Hz written as a ROS 1 bag with rosbag.

Reference /optitrack/head (PoseStamped) and estimate /rtabmap/odom (Odometry) share stamps
100.0 .. 130.0 s. The estimate is the reference plus a constant offset per mission leg (known errors):
leg 0 (100-110 s) +0.1 m in x, leg 1 (110-120 s) +0.3 m in y, done (120-130 s) +0.2 m in z.
Tracking loss in the estimate: covariance 9999 for 112.0-113.0 s (the first half also a null pose),
no messages for 115.0-117.9 s (a 3.1 s gap), a lone null pose at 125.0 s, and the tracker reports
pose_stale at 121 and 122 s. /tf holds map->odom (static) and odom->base_link = the clean estimate.
"""
import numpy as np

T0_NS = 100 * 10**9
STEP_NS = 10**8          # 10 Hz
N = 301                  # 100.0 .. 130.0 s
LEG_OFFSETS = {0: (0.1, 0.0, 0.0), 1: (0.0, 0.3, 0.0), 2: (0.0, 0.0, 0.2)}
LEG_ERRORS = {"waypoint 0": 0.1, "waypoint 1": 0.3, "done": 0.2}
GAITS = {0: "sidewind", 1: "rolling", 2: "sidewind"}
# expected after exclusion (see module docstring)
EXPECTED_PAIRS = {"waypoint 0": 100, "waypoint 1": 59, "done": 81}
EXPECTED_EXCLUDED = 19   # 121.1 .. 122.9 s (pose_stale)


def stamp_ns(k: int) -> int:
    return T0_NS + k * STEP_NS


def leg_of(t_s: float) -> int:
    return 0 if t_s < 110.0 else (1 if t_s < 120.0 else 2)


def reference_pose(t_s: float):
    """A smooth xy loop at z 0.1 m, heading along the path: (xyz, quat xyzw)."""
    u = (t_s - 100.0) / 30.0 * 2 * np.pi
    xyz = np.array([2.0 * np.sin(u), 1.0 - np.cos(u), 0.1 + 0.02 * np.sin(3 * u)])
    yaw = np.arctan2(np.sin(u), np.cos(u))
    return xyz, np.array([0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)])


def estimate_pose(t_s: float):
    xyz, q = reference_pose(t_s)
    return xyz + np.array(LEG_OFFSETS[leg_of(t_s)]), q


def lost_covariance(k: int) -> bool:
    return 120 <= k <= 130          # 112.0 .. 113.0 s


def null_pose(k: int) -> bool:
    return 120 <= k <= 125 or k == 250   # 112.0 .. 112.5 s and 125.0 s


def dropped(k: int) -> bool:
    return 150 <= k <= 179          # 115.0 .. 117.9 s: no message at all


def write_run_bag(path, with_status: bool = True, with_tf: bool = True) -> str:
    import rosbag
    import rospy
    from geometry_msgs.msg import PoseStamped, TransformStamped
    from nav_msgs.msg import Odometry
    from tf2_msgs.msg import TFMessage

    bag = rosbag.Bag(str(path), "w")
    try:
        if with_tf:
            static = TransformStamped()
            static.header.stamp = rospy.Time(nsecs=T0_NS)
            static.header.frame_id, static.child_frame_id = "map", "odom"
            static.transform.rotation.w = 1.0
            bag.write("/tf_static", TFMessage([static]), static.header.stamp)
        for k in range(N):
            stamp = rospy.Time(nsecs=stamp_ns(k))
            t_s = stamp.to_sec()
            xyz, q = reference_pose(t_s)
            ref = PoseStamped()
            ref.header.stamp, ref.header.frame_id = stamp, "world"
            _fill_pose(ref.pose, xyz, q)
            bag.write("/optitrack/head", ref, stamp)
            if dropped(k):
                continue
            xyz_e, q_e = estimate_pose(t_s)
            if with_tf:
                tf = TransformStamped()
                tf.header.stamp, tf.header.frame_id, tf.child_frame_id = stamp, "odom", "base_link"
                tf.transform.translation.x, tf.transform.translation.y, tf.transform.translation.z = xyz_e
                (tf.transform.rotation.x, tf.transform.rotation.y, tf.transform.rotation.z,
                 tf.transform.rotation.w) = q_e
                bag.write("/tf", TFMessage([tf]), stamp)
            odom = Odometry()
            odom.header.stamp, odom.header.frame_id, odom.child_frame_id = stamp, "odom", "base_link"
            if null_pose(k):
                xyz_e, q_e = np.zeros(3), np.zeros(4)
            _fill_pose(odom.pose.pose, xyz_e, q_e)
            cov = [0.0] * 36
            for d in (0, 7, 14, 21, 28, 35):
                cov[d] = 9999.0 if lost_covariance(k) else 1e-4
            odom.pose.covariance = cov
            bag.write("/rtabmap/odom", odom, stamp)
        if with_status:
            from snake_autonomy.msg import TrackingStatus
            for second in range(100, 131):
                msg = TrackingStatus()
                msg.header.stamp = rospy.Time(second)
                leg = leg_of(float(second))
                msg.waypoint_index, msg.num_waypoints = min(leg, 2), 2
                msg.done = leg == 2
                msg.gait = GAITS[leg]
                msg.mode = 1 if second % 10 < 7 else 3
                msg.pose_stale = second in (121, 122)
                bag.write("/tracking_status", msg, msg.header.stamp)
    finally:
        bag.close()
    return str(path)


def _fill_pose(pose, xyz, q):
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in xyz)
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = (float(v) for v in q)


def write_tum(path, stamps, xyz, quat_xyzw) -> str:
    with open(path, "w") as f:
        for t, p, q in zip(stamps, xyz, quat_xyzw):
            f.write(f"{t:.9f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n")
    return str(path)
