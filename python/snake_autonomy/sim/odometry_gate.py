"""Camera odometry to base_link's pose as pose_remap_node does it, ROS-free: the tracking gate (lost,
stale, jumps: config/camera.yaml lost_tracking) then eq. 3.1 (camera_in_head of config/camera.yaml,
H of the robot YAML). The simulated pose sources share it (sim/feedback.VioFeedback,
sim/vo_feedback.VoFeedback), so a lost or stale odometry holds the robot exactly as on the ROS path.

    g = GatedRemap(params, robot)
    T = g.base_in_world(sample)        # a PoseSample of the camera in the odometry frame -> 4x4, or None
    ok, detail = g.status(t_s)
"""
from typing import Optional

import numpy as np

from ..estimation import PoseRemapper, TrackingGate, load_camera_calibration, load_gate_params
from ..transforms import make_transform, quat_to_matrix


class GatedRemap:
    def __init__(self, params, robot):
        cfg = params.config
        calibration = load_camera_calibration(cfg.calibration_path())
        self.gate = TrackingGate(load_gate_params(cfg.calibration_path()))
        self.remapper = PoseRemapper(calibration.camera_in_head, robot.head_length_m)

    def base_in_world(self, s) -> Optional[np.ndarray]:
        """One odometry sample through the gate and eq. 3.1: base_link's 4x4 pose, or None when the
        gate refuses it (lost, invalid, a jump)."""
        result = self.gate.check(s.t_s, s.position_m, s.quat_xyzw, np.diag(s.covariance))
        if not result.ok:
            return None
        camera_in_world = make_transform(quat_to_matrix(*s.quat_xyzw), s.position_m)
        return self.remapper.base_in_world(camera_in_world)

    def status(self, t_s: float):
        state, detail = self.gate.state_at(t_s)
        return state == "ok", f"{state}: {detail}"
