"""Where the driver's base pose comes from in a simulated run: motion capture or the simulated
RTAB-Map through the pose remapper (thesis eq. 3.1 and its lost-tracking gate).

    fb = make_feedback("vio", params, robot)       # or "mocap"
    pose = fb.poll(plant)          # (t_s, position (3,), quat_xyzw (4,)) of base_link, or None
    ok, detail = fb.status(t_s)    # the pose source's verdict (what base_pose_status carries)

`mocap`: MocapSensor (base_link, 100 Hz) straight into the driver, as in the thesis's experiments.
`vio`: SimulatedVio (camera odometry, 30 Hz, noise, drift, tracking losses) -> TrackingGate (lost,
stale, jumps: config/camera.yaml lost_tracking) -> PoseRemapper (eq. 3.1, camera_in_head of
config/camera.yaml, H of the robot YAML): the classes pose_remap_node wraps, so a lost or stale
odometry holds the robot (ERRATA #7) exactly as on the ROS path.

Both record what they measured, for the evaluation after a run (`samples`).
"""
from typing import List, Optional, Tuple

import numpy as np

from ..estimation import PoseRemapper, TrackingGate, load_camera_calibration, load_gate_params
from ..transforms import make_transform, matrix_to_pose, quat_to_matrix
from .mocap import MocapSensor
from .vio import SimulatedVio

FEEDBACKS = ("mocap", "vio")
Pose = Tuple[float, np.ndarray, np.ndarray]


class MocapFeedback:
    name = "mocap"

    def __init__(self, params):
        self.sensor = MocapSensor(params)
        self.samples: List[tuple] = []

    def poll(self, plant) -> Optional[Pose]:
        s = self.sensor.poll(plant)
        if s is None:
            return None
        return s.t_s, s.position_m, s.quat_xyzw

    def status(self, t_s: float):
        return True, "motion capture"


class VioFeedback:
    """Simulated RTAB-Map -> gate -> eq. 3.1. `samples` keeps (t, estimate pos, quat, lost, true pos,
    true quat) of the camera for the evaluation (the truth is the plant's camera pose)."""
    name = "vio"

    def __init__(self, params, robot):
        cfg = params.config
        calibration = load_camera_calibration(cfg.calibration_path())
        self.vio = SimulatedVio(params, calibration.camera_in_head)
        self.gate = TrackingGate(load_gate_params(cfg.calibration_path()))
        self.remapper = PoseRemapper(calibration.camera_in_head, robot.head_length_m)
        self.samples: List[tuple] = []

    def poll(self, plant) -> Optional[Pose]:
        if not self.vio.clock.due(plant.time_s):
            return None
        world_t_head = plant.frame_transform("head_link")
        s = self.vio.measure(plant.time_s, world_t_head)
        true_cam = world_t_head @ self.vio.head_t_camera
        tp, tq = matrix_to_pose(true_cam)
        self.samples.append((s.t_s, s.position_m.copy(), s.quat_xyzw.copy(), s.lost, np.asarray(tp), np.asarray(tq)))
        cov = np.diag(s.covariance)
        result = self.gate.check(s.t_s, s.position_m, s.quat_xyzw, cov)
        if not result.ok:
            return None
        camera_in_world = make_transform(quat_to_matrix(*s.quat_xyzw), s.position_m)
        p, q = matrix_to_pose(self.remapper.base_in_world(camera_in_world))
        return s.t_s, np.asarray(p, float), np.asarray(q, float)

    def status(self, t_s: float):
        state, detail = self.gate.state_at(t_s)
        return state == "ok", f"{state}: {detail}"


def make_feedback(kind: str, params, robot):
    if kind == "mocap":
        return MocapFeedback(params)
    if kind == "vio":
        return VioFeedback(params, robot)
    raise ValueError(f"feedback: expected one of {', '.join(FEEDBACKS)}, got {kind!r}")
