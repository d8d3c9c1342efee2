"""Follow-the-leader curvature for the rectilinear gait (a prototype on the Python
reference gait; the driver's steering laws do not have it yet).

The `curvature` steering law bends every lateral joint to the commanded kappa at once: the body
reshapes about its middle and its ends swing (L^2/8) dkappa sideways (0.28 m per 1/m on COBRA), the
touches seen when turning past an obstacle. Here the commanded kappa is the curvature
of the HEAD's path where the head is now; it is laid down along the path as the head crawls, and
each yaw joint bends to the mean curvature of the path under the span it covers (spacing_m, ending
at the joint's own place on the path). The body then lies on the head's path like a train on its
track (bench/nav_follow_the_leader, the gait through the driver: the farthest any frame strays from
the track in a 1.5 /m turn, 0.11 m against 0.37 m with uniform curvature; at 2.5 /m 0.11 against
0.54 m).

Backing off (the head's arc position decreasing) lays nothing down: the joints take the curvature of
the path behind them again, so the body retraces its track exactly.

Measured in the navigation experiment (COBRA mono 20 x 5, the former batch loop): 65 % (9 runs
touching, 24 time limits) against 75 % with uniform curvature (16 touching, 4 time limits), so not
the default. The navigation loop (nav_loop.py, planner_node and nav runs) commands uniform
curvature only (`gaits.steering: follow_the_leader` is refused there); a navigation loop with it
would send these per-joint biases in the gait command.

Arc positions: s_head is the head's distance crawled along its path (from the start, forward
positive); the body behind the start lies straight (curvature 0).
"""
from typing import Sequence

import math

import numpy as np


class FollowTheLeader:
    def __init__(self, joint_offsets_m: Sequence[float], spacing_m: float, resolution_m: float = 0.005,
                 body_length_m: float = 2.0, yaw_joints: Sequence[int] = (), num_joints: int = 0):
        """joint_offsets_m: each yaw joint's distance behind the first yaw joint (head to tail);
        spacing_m: the yaw joints' spacing (the span of path each one bends over); yaw_joints and
        num_joints: where the curvatures go in a joint vector (biases())."""
        self.yaw_joints, self.num_joints = list(yaw_joints), int(num_joints)
        self._last = None
        self.offsets = np.asarray(joint_offsets_m, float)
        if self.offsets.ndim != 1 or not len(self.offsets) or (np.diff(self.offsets) < 0).any():
            raise ValueError(f"joint_offsets_m: expected increasing offsets, got {joint_offsets_m!r}")
        if not spacing_m > 0 or not resolution_m > 0:
            raise ValueError(f"spacing_m and resolution_m must be > 0, got {spacing_m}, {resolution_m}")
        self.spacing_m, self.res = float(spacing_m), float(resolution_m)
        self._origin = int(np.ceil((body_length_m + self.offsets[-1] + spacing_m) / self.res))
        self._path = np.zeros(self._origin + 1024)        # curvature per cell of arc length
        self.s_head_m = 0.0

    @classmethod
    def of_robot(cls, robot, resolution_m: float = 0.005) -> "FollowTheLeader":
        """From a RobotModel: its yaw joints at s_i = H + (i - 1) L (planning/rectilinear/gait.py)."""
        axes = list(robot.axes)
        yaw = [i for i, a in enumerate(axes) if a == "yaw"]
        if len(yaw) < 2:
            raise ValueError(f"follow-the-leader steering needs 2 or more yaw joints, {robot.name} has {len(yaw)}")
        s_yaw = robot.head_length_m + robot.link_length_m * np.asarray(yaw, float)
        return cls(s_yaw - s_yaw[0], float(np.mean(np.diff(s_yaw))), resolution_m,
                   body_length_m=robot.head_length_m + robot.link_length_m * len(axes),
                   yaw_joints=yaw, num_joints=len(axes))

    def crawl(self, pose, kappa_per_m: float) -> None:
        """The head's new pose (x, y, theta) on the floor: its move along its heading since the last
        pose is the crawl (ground truth in the simulator; odometry on a robot)."""
        if self._last is not None:
            x, y, th = pose
            self.advance((x - self._last[0]) * math.cos(th) + (y - self._last[1]) * math.sin(th), kappa_per_m)
        self._last = (float(pose[0]), float(pose[1]))

    def biases(self) -> np.ndarray:
        """A joint vector: each yaw joint's bend, kappa x spacing (the driver's curvature law's sign,
        src/core/curvature_steering.cpp), the other joints 0."""
        out = np.zeros(self.num_joints)
        out[self.yaw_joints] = self.joint_kappas() * self.spacing_m
        return out

    def _cell(self, s_m: float) -> int:
        return self._origin + int(np.floor(s_m / self.res))

    def advance(self, ds_m: float, kappa_per_m: float) -> None:
        """The head crawled ds_m along its path (< 0: backing off) while commanding kappa_per_m;
        forward motion lays kappa down on the path it covered."""
        if ds_m > 0:
            a, b = self._cell(self.s_head_m), self._cell(self.s_head_m + ds_m)
            if b + 1 >= len(self._path):
                self._path = np.concatenate([self._path, np.zeros(max(1024, b + 2 - len(self._path)))])
            self._path[a:b + 1] = kappa_per_m
        self.s_head_m = max(self.s_head_m + ds_m, -self._origin * self.res + self.offsets[-1] + self.spacing_m)

    def joint_kappas(self) -> np.ndarray:
        """Each yaw joint's curvature: the path's mean over the span (spacing_m) ending at its place."""
        out = np.empty(len(self.offsets))
        for j, off in enumerate(self.offsets):
            end = self._cell(self.s_head_m - off)
            start = self._cell(self.s_head_m - off - self.spacing_m)
            out[j] = float(np.mean(self._path[start:end + 1]))
        return out
