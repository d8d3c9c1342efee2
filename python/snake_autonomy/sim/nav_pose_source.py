"""The base pose a navigation run's loop gets (runs/nav_batch.py), with its latency, and how far it
was from the truth.

    source = NavPoseSource("vio", params, robot)       # mocap | truth | vio | vo (vo: plant= too)
    source.step_to(plant, t_s)                          # the physics to t_s (vo: via the IMU's samples)
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
- `vo`: the visual-inertial odometry vio_node runs, on its own camera (sim/vo_feedback.VoFeedback:
  camera_link's colour + depth at 320x240, 10 Hz, rendered apart from the planner's frames) and the
  head camera's 200 Hz IMU, through the same gate and remapper; the plant must carry the IMU
  (Plant(imu_in_head=imu_in_head("vo", params))) and be stepped by step_to, which stops the physics
  at the IMU's sample times. The odometry frame is anchored to the world at its first frame (2.3 s,
  after the gyro's calibration at rest: VoFeedback.start_s; the robot lying still). Latency
  config/sim.yaml vio.latency_s, as vio's. It needs something to see: runs refuse it on a world whose
  floor_texture is not an odometry floor (runs/nav_batch.NavRunSpec.check,
  sim/world_file.ODOMETRY_FLOOR_TEXTURES).

Errors are measured at every pose delivered: base_link's position on the floor (x, y) and yaw
against the plant's at the sample's stamp (vo: at the frame's world step, one 2 ms physics step after
its stamp).
"""
import math
from typing import Optional, Tuple

import numpy as np

from ..estimation import load_camera_calibration
from ..transforms import pose_to_matrix
from .feedback import VioFeedback
from .imu import ImuSensor
from .mocap import MocapSensor
from .vio import SimulatedVio
from .vo_feedback import VoFeedback
from .world import WorldStep

POSE_SOURCES = ("mocap", "truth", "vio", "vo")
MOCAP_LATENCY_S = 0.01         # motion capture sample to the planner


def imu_in_head(kind: str, params) -> Optional[np.ndarray]:
    """The IMU's 4x4 pose in head_link (config/camera.yaml camera_in_head) the plant must carry for
    the pose source `kind` (Plant(imu_in_head=...)), or None: only vo reads the IMU."""
    return load_camera_calibration(params.config.calibration_path()).camera_in_head if kind == "vo" else None


class _ImuWorld:
    """What VoFeedback reads of a world: the plant with its IMU, the seed's parameters, camera_in_head."""

    def __init__(self, plant, params):
        self.plant, self.params = plant, params
        self.camera_in_head = imu_in_head("vo", params)
        self.imu = ImuSensor(params.config.imu, params.rng("imu"), step_s=plant.dt_s)


class NavPoseSource:
    def __init__(self, kind: str, params, robot, plant=None):
        """plant: the run's plant (vo only: built with imu_in_head(kind, params))."""
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
        self.vo, self._imu = None, []
        if kind == "vo":
            if plant is None:
                raise ValueError("pose_source vo: needs the run's plant (NavPoseSource(..., plant=))")
            self.vo = VoFeedback(_ImuWorld(plant, params), robot)
            self.latency_s = float(params.config.vio.latency_s)
            self._vio_period_s = 1.0 / self.vo.camera.settings.rate_hz
        self.lost_s, self.lost_episodes, self.refused = 0.0, 0, 0
        self._was_lost = False
        self._n, self._sq, self._max_xy, self._max_yaw = 0, 0.0, 0.0, 0.0

    def step_to(self, plant, t_s: float) -> None:
        """The plant's physics to t_s; with vo it stops at the IMU's sample times on the way and keeps
        the samples for the next poll."""
        if self.vo is None:
            plant.step_to(t_s)
            return
        imu = self.vo.world.imu
        self._imu += imu.step_plant_to(plant, t_s)
        s = imu.poll(plant)
        if s is not None:
            self._imu.append(s)

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
        elif self.kind == "vo":
            n = len(self.vo.samples)
            imu, self._imu = self._imu, []
            p = self.vo.pose(WorldStep(t, imu_between=imu))
            if p is None:
                if len(self.vo.samples) > n:       # a frame's odometry the gate refused
                    self._lost()
                return None
            self._was_lost = False
            out = (p[0], pose_to_matrix(p[1], p[2]))
        else:
            s = self.vio.poll(plant)
            if s is None:
                return None
            T = self.feedback.base_in_world(s)
            if T is None:
                self._lost()
                return None
            self._was_lost = False
            out = (s.t_s, T)
        self._error(out[1], truth)
        return out

    def _lost(self) -> None:
        self.refused += 1
        self.lost_s += self._vio_period_s
        self.lost_episodes += not self._was_lost
        self._was_lost = True

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
        pose_refused (samples); with vo also vo_frames, vo_ms_median (the odometry's time per frame) and
        vo_render_ms_median (its camera's render)."""
        rmse = math.sqrt(self._sq / self._n) if self._n else None
        return {"pose_source": self.kind, "pose_samples": self._n,
                "pose_error_xy_rmse_m": None if rmse is None else round(rmse, 5),
                "pose_error_xy_max_m": round(self._max_xy, 5) if self._n else None,
                "pose_error_yaw_max_deg": round(self._max_yaw, 3) if self._n else None,
                "tracking_lost_s": round(self.lost_s, 3), "tracking_lost_episodes": self.lost_episodes,
                "pose_refused": self.refused, **self._vo_metrics()}

    def _vo_metrics(self) -> dict:
        if self.vo is None:
            return {}
        s = self.vo.summary()
        return {"vo_frames": s["frames"], "vo_ms_median": round(s["ms_median"], 2),
                "vo_render_ms_median": round(s["render_ms_median"], 2)}

    def close(self) -> None:
        if self.vo is not None:
            self.vo.close()
