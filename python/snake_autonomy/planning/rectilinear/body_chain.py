"""The body as it lies: its stations from the joints' angles, ROS-free.

The uniform-arc model (body_model.py) places the body as one arc of the commanded curvature through
base_link. The robot's body is not that arc: its curvature sits in a few yaw joints (the 12-link
robot: 5, one every 0.14 m, none in the head and first link), the joints lag the command while the
bias slews, and the pitch joints' wave lifts parts of it. The chain's forward kinematics of the
measured joint angles (joint_states: the driver's present positions) place every link where it is:

    chain = BodyChain(robot)                        # a _core.RobotModel
    state = BodyState(q, T_ground_base)            # measured angles, base_link's pose in the ground frame
    xy = chain.stations(state.q, state.T_ground_base[:3, :3], arc_from_base_m)     # (N, 2) on the floor

The forward kinematics are the core's (_core.Kinematics: KDL, the driver's own); the curvature a
command bends the body to is the driver's steering law (_core.CurvatureSteering: yaw bias = kappa x
the yaw joints' spacing). body_sweep.BodySweep reshapes the body from these angles to the command's
in joint space (the servos' own path) and carries the new shape along its crawl.
"""
from dataclasses import dataclass
from typing import Optional

import numpy as np

from snake_autonomy import _core
from snake_autonomy.transforms import matrix_to_quat

from .body_model import BodyGeometry


@dataclass(frozen=True)
class BodyState:
    """The body as the joints measured it at one instant."""
    q: np.ndarray                 # (num_joints,) joint angles (rad), joint_1 .. joint_N
    T_ground_base: np.ndarray     # 4x4 base_link's pose in the replan's ground frame (its tilt: the head bobs)


class BodyChain:
    def __init__(self, robot):
        """robot: a _core.RobotModel (its frames: base_link at the head's front, head, link_1 ..
        link_N, the last at the tail's end)."""
        self.robot = robot
        self.geometry = BodyGeometry.of_robot(robot)
        self.num_joints = int(robot.num_joints)
        self._kin = _core.Kinematics(robot)
        self._steer = _core.CurvatureSteering(robot)
        self._yaw = np.asarray(self._steer.yaw_joints, int)
        # each frame's arc length from base_link: the links are rigid, whatever the joints
        straight = self.frames(np.zeros(self.num_joints))
        self._along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(straight, axis=0), axis=1))])

    def bent(self, q: np.ndarray, kappa_per_m: float) -> np.ndarray:
        """q with its yaw joints at the biases the driver commands for kappa_per_m (the pitch joints kept)."""
        out = np.asarray(q, float).copy()
        out[self._yaw] = self._steer.modify_biases(np.zeros(self.num_joints), float(kappa_per_m))[self._yaw]
        return out

    def frames(self, q: np.ndarray, R_ground_base: Optional[np.ndarray] = None) -> np.ndarray:
        """(F, 3) the chain's frame origins, base_link to the tail's end, with base_link at the origin
        tilted by R_ground_base (None: level)."""
        return self._frames(np.asarray(q, float), _quat(R_ground_base))

    def stations(self, q: np.ndarray, R_ground_base: Optional[np.ndarray], arc_m: np.ndarray) -> np.ndarray:
        """(N, 2) the points of the body at arc lengths arc_m from base_link along the chain, on the
        floor (the links are straight between the frames); q (K, num_joints): (K, N, 2), one body each."""
        q = np.asarray(q, float)
        quat = _quat(R_ground_base)
        p = np.stack([self._frames(qk, quat)[:, :2] for qk in np.atleast_2d(q)])     # (K, F, 2)
        x = np.interp(np.clip(arc_m, 0.0, self._along[-1]), self._along, np.arange(len(self._along)))
        i = np.minimum(x.astype(int), len(self._along) - 2)
        f = (x - i)[None, :, None]
        out = p[:, i] * (1.0 - f) + p[:, i + 1] * f
        return out if q.ndim == 2 else out[0]

    def _frames(self, q: np.ndarray, quat) -> np.ndarray:
        return np.asarray(self._kin.compute(np.zeros(3), quat, q).link_positions)


def _quat(R_ground_base: Optional[np.ndarray]):
    return matrix_to_quat(np.eye(3) if R_ground_base is None else np.asarray(R_ground_base, float))
