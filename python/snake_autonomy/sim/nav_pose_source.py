"""The base pose a navigation run's loop gets (runs/nav_batch.py), with its latency, and how far it
was from the truth.

    source = NavPoseSource("vio", params, robot)       # mocap | truth | vio
    sample = source.poll(plant)                         # (stamp, 4x4 base_link in the world) or None
    loop.on_pose(*sample) pose_latency_s later          # source.latency_s unless the run overrides it
    source.metrics()                                    # pose error vs the truth, tracking lost (s)

- `mocap`: motion capture of base_link (sim/mocap.py, config/sim.yaml mocap:), as sim.launch
  feedback:=mocap; latency MOCAP_LATENCY_S.
- `truth`: the plant's base_link at every call, no noise (a diagnostic); latency MOCAP_LATENCY_S.
- `vio`: the simulated RTAB-Map (sim/vio.py: noise, drift, tracking losses) through the tracking
  gate and the pose remapper (sim/feedback.VioFeedback: the classes pose_remap_node wraps); latency
  config/sim.yaml vio.latency_s. A sample the gate refuses (lost, invalid, a jump) gives no pose:
  the loop holds on a stale pose after its pose_timeout_s, as planner_node does.

Errors are measured at every pose delivered: base_link's position on the floor (x, y) and yaw
against the plant's at the sample's stamp.
"""
import math
from typing import Optional, Tuple

import numpy as np

from ..estimation import load_camera_calibration
from ..transforms import pose_to_matrix
from .feedback import VioFeedback
from .mocap import MocapSensor
from .vio import SimulatedVio

POSE_SOURCES = ("mocap", "truth", "vio")
MOCAP_LATENCY_S = 0.01         # motion capture sample to the planner


class NavPoseSource:
    def __init__(self, kind: str, params, robot):
        if kind not in POSE_SOURCES:
            raise ValueError(f"pose_source: expected one of {', '.join(POSE_SOURCES)}, got {kind!r}")
        self.kind = kind
        self.mocap = MocapSensor(params) if kind == "mocap" else None
        self.vio = self.feedback = None
        self.latency_s = MOCAP_LATENCY_S
        if kind == "vio":
            cfg = params.config
            self.vio = SimulatedVio(params, load_camera_calibration(cfg.calibration_path()).camera_in_head)
            self.feedback = VioFeedback(params, robot)
            self.latency_s = float(cfg.vio.latency_s)
            self._vio_period_s = 1.0 / float(cfg.vio.rate_hz)
        self.lost_s, self.lost_episodes, self.refused = 0.0, 0, 0
        self._was_lost = False
        self._n, self._sq, self._max_xy, self._max_yaw = 0, 0.0, 0.0, 0.0

    def poll(self, plant) -> Optional[Tuple[float, np.ndarray]]:
        """(stamp, base_link's 4x4 in the world) of the sample due at plant.time_s, else None."""
        t = plant.time_s
        truth = plant.frame_transform("base_link")
        if self.kind == "truth":
            out = (t, truth)
        elif self.kind == "mocap":
            s = self.mocap.poll(plant)
            if s is None:
                return None
            out = (s.t_s, pose_to_matrix(s.position_m, s.quat_xyzw))
        else:
            s = self.vio.poll(plant)
            if s is None:
                return None
            T = self.feedback.base_in_world(s)
            if T is None:
                self.refused += 1
                self.lost_s += self._vio_period_s
                self.lost_episodes += not self._was_lost
                self._was_lost = True
                return None
            self._was_lost = False
            out = (s.t_s, T)
        self._error(out[1], truth)
        return out

    def _error(self, T: np.ndarray, truth: np.ndarray) -> None:
        d = float(math.hypot(T[0, 3] - truth[0, 3], T[1, 3] - truth[1, 3]))
        yaw = math.atan2(T[1, 0], T[0, 0]) - math.atan2(truth[1, 0], truth[0, 0])
        yaw = abs(math.degrees(math.atan2(math.sin(yaw), math.cos(yaw))))
        self._n += 1
        self._sq += d * d
        self._max_xy, self._max_yaw = max(self._max_xy, d), max(self._max_yaw, yaw)

    def metrics(self) -> dict:
        """pose_source, pose_samples (delivered), pose_error_xy_rmse_m / _max_m, pose_error_yaw_max_deg,
        tracking_lost_s (odometry samples the gate refused x their period), tracking_lost_episodes,
        pose_refused (samples)."""
        rmse = math.sqrt(self._sq / self._n) if self._n else None
        return {"pose_source": self.kind, "pose_samples": self._n,
                "pose_error_xy_rmse_m": None if rmse is None else round(rmse, 5),
                "pose_error_xy_max_m": round(self._max_xy, 5) if self._n else None,
                "pose_error_yaw_max_deg": round(self._max_yaw, 3) if self._n else None,
                "tracking_lost_s": round(self.lost_s, 3), "tracking_lost_episodes": self.lost_episodes,
                "pose_refused": self.refused}
