"""RunMission's inline waypoints in a frame of their own (goal.frame_id), brought into the mission's world
frame (mission_node's ~world_frame) with tf2 before the goal becomes a mission.

Empty frame_id, or the world frame: the waypoints are taken as they are (the clients before frame_id).
Another frame: each waypoint's position and heading go through the latest transform world <- frame
(its yaw; the waypoints lie on the world's ground plane), waited for TF_WAIT_S at most. A frame tf does
not know, or a frame_id with a mission file or mission_yaml (their waypoints are in the world frame),
refuses the goal with a MissionError naming the frame.

The tf2 listener is made at the first goal in another frame: a Python listener decodes every /tf
message (the driver's and the robot state publisher's, 100 Hz), CPU a mission in the world frame never needs.
"""
import copy
import math

import numpy as np
import rospy
import tf2_ros

from snake_autonomy.missions import MissionError
from snake_autonomy.transforms import quat_to_matrix

TF_WAIT_S = 2.0     # a transform not known this long after the goal came: the goal is refused
SOURCE = "RunMission goal frame_id"


class GoalFrames:
    def __init__(self, world_frame: str, wait_s: float = TF_WAIT_S):
        self.world_frame, self.wait_s = world_frame, wait_s
        self.tf = self.tf_listener = None

    def to_world(self, goal):
        """The goal with its inline waypoints in the world frame (a copy, frame_id emptied), or the goal
        itself when they already are; MissionError naming the frame when they cannot be."""
        frame, world = goal.frame_id, self.world_frame
        if not frame or frame == world:
            return goal
        if not goal.waypoints:
            raise MissionError(SOURCE, [f"frame_id {frame!r}: only inline waypoints take a frame (a mission "
                                        f"file's or mission_yaml's waypoints are in the world frame {world!r})"])
        if self.tf is None:
            self.tf = tf2_ros.Buffer()
            self.tf_listener = tf2_ros.TransformListener(self.tf)
        try:
            t = self.tf.lookup_transform(world, frame, rospy.Time(0), rospy.Duration(self.wait_s)).transform
        except tf2_ros.TransformException as exc:
            raise MissionError(SOURCE, [f"frame_id {frame!r}: no transform to the world frame {world!r} within "
                                        f"{self.wait_s:g} s ({str(exc).strip()})"]) from None
        r, v = t.rotation, t.translation
        rotation = quat_to_matrix(r.x, r.y, r.z, r.w)
        out = copy.deepcopy(goal)
        for p in out.waypoints:
            x, y, _ = rotation @ np.array([p.x, p.y, 0.0]) + (v.x, v.y, v.z)
            dx, dy, _ = rotation @ np.array([math.cos(p.theta), math.sin(p.theta), 0.0])
            p.x, p.y, p.theta = float(x), float(y), math.atan2(dy, dx)
        out.frame_id = ""
        return out
