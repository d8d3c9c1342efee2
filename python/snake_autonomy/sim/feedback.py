"""Where the driver's base pose comes from in a simulated run: motion capture or the simulated
RTAB-Map through the pose remapper (thesis eq. 3.1 and its lost-tracking gate).

    fb = make_feedback("vio", params, robot)       # or "mocap"; "vo": make_feedback("vo", params, robot, world)
    out = world.step_to(t_s)       # the SimWorld samples the sensors (sim.world)
    pose = fb.pose(out)            # (t_s, position (3,), quat_xyzw (4,)) of base_link, or None
    ok, detail = fb.status(t_s)    # the pose source's verdict (what base_pose_status carries)

`mocap`: the world's motion capture sample (base_link, 100 Hz) straight into the driver, as in the
thesis's experiments. `vio`: its simulated RTAB-Map sample (camera odometry, 30 Hz, noise, drift,
tracking losses) -> TrackingGate (lost, stale, jumps: config/camera.yaml lost_tracking) ->
PoseRemapper (eq. 3.1, camera_in_head of config/camera.yaml, H of the robot YAML), sim/odometry_gate.py:
the classes pose_remap_node wraps, so a lost or stale odometry holds the robot exactly as on the
ROS path. `vo`: the visual-inertial odometry on rendered frames and the IMU, through the same gate
and remapper (sim/vo_feedback.py). `sensor`: the world sensor each needs (WorldSpec.sensors).

VioFeedback records what it measured, for the evaluation after a run (`samples`).
"""
from typing import List, Optional, Tuple

import numpy as np

from ..transforms import matrix_to_pose
from .odometry_gate import GatedRemap
from .vo_feedback import VoFeedback
from .world import FEEDBACKS

Pose = Tuple[float, np.ndarray, np.ndarray]


class MocapFeedback:
    name = sensor = "mocap"

    def __init__(self):
        self.samples: List[tuple] = []

    def pose(self, out) -> Optional[Pose]:
        s = out.mocap
        if s is None:
            return None
        return s.t_s, s.position_m, s.quat_xyzw

    def status(self, t_s: float):
        return True, "motion capture"


class VioFeedback(GatedRemap):
    """Simulated RTAB-Map -> gate -> eq. 3.1 (GatedRemap). `samples` keeps (t, estimate pos, quat, lost,
    true pos, true quat) of the camera for the evaluation (the truth is the plant's camera pose)."""
    name = sensor = "vio"

    def __init__(self, params, robot):
        super().__init__(params, robot)
        self.samples: List[tuple] = []

    def pose(self, out) -> Optional[Pose]:
        s = out.vio
        if s is None:
            return None
        tp, tq = out.truth_camera
        self.samples.append((s.t_s, s.position_m.copy(), s.quat_xyzw.copy(), s.lost, np.asarray(tp), np.asarray(tq)))
        T = self.base_in_world(s)
        if T is None:
            return None
        p, q = matrix_to_pose(T)
        return s.t_s, np.asarray(p, float), np.asarray(q, float)


def make_feedback(kind: str, params, robot, world=None):
    """world: the SimWorld (kind vo renders its frames from its plant and reads its IMU)."""
    if kind == "mocap":
        return MocapFeedback()
    if kind == "vio":
        return VioFeedback(params, robot)
    if kind == "vo":
        if world is None:
            raise ValueError("feedback vo: needs the world (make_feedback(..., world=...))")
        return VoFeedback(world, robot)
    raise ValueError(f"feedback: expected one of {', '.join(FEEDBACKS)}, got {kind!r}")
