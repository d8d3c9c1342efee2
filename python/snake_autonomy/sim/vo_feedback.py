"""The batch simulator's `vo` pose source: the visual-inertial odometry vio_node runs
(estimation/vio_stream.VioStream over estimation/vio_fusion.VioFusion, config/estimation.yaml) fed in
lock-step with the head camera's frames rendered here and the world's IMU samples; its odometry then
goes through the tracking gate and the pose remapper (sim/odometry_gate.GatedRemap: the classes
pose_remap_node wraps) into the driver. The ROS path's sim.launch feedback:=vo, without the transport.

    fb = VoFeedback(world, robot)     # the world with the IMU among its sensors and something to see
                                      # (sim/scene.vo_room; runs/batch.py puts the run in one)
    pose = fb.pose(out)               # every world step: its IMU samples in, a frame rendered when due;
                                      # base_link's (t, position, quat) when a frame's odometry passed the gate
    ok, detail = fb.status(t_s)       # the gate's verdict
    fb.summary()                      # frames, lost intervals and their causes, ms per frame and render
    fb.samples                        # (stamp, estimate pos, quat, lost, true pos, true quat) of camera_link

The camera (OdometryCamera): sim_node's odometry camera, ODOMETRY_CAMERA (320x240, the D435i's
615 px focal length scaled, 10 Hz), at camera_link (sim/mjcf.camera_link_in_base: the IMU's site),
colour and depth only, the depth through the D435i-like model (config/sim.yaml depth_noise:, the
seed's "depth_noise" stream). Frames fall on the rate's grid of simulated time; each shows the state
of MuJoCo's last forward pass and carries its time (Plant.imu_truth's, one physics step back), as
the IMU's samples do. A frame waits for the IMU sample at its stamp, as vio_node's does (imu_wait_s
infinite: in lock-step that sample comes in the same world step).

The odometry's frame: the fusion starts level on gravity, with zero yaw, at camera_link's first
frame (as vio_node's), start_s into the run with the robot lying still: the IMU's samples are fed
from REST_FROM_S (the plant has settled on the floor), and the first frame comes LEVELLING_S plus the
fusion's rest window (fusion.rest_calibration_s: the gyro calibrated at rest) after that; the
mission holds the robot until the first pose. It is anchored to the world once, at that frame, by
the camera's true position and heading then (the simulated RTAB-Map's odometry frame is the world's
at the start, too); from then on only the estimate moves it.

blackouts: [(start_s, end_s)] of simulated time in which the frames are black with no depth (a
covered lens), to test lost tracking.
"""
import math
import time
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from ..estimation.vio_fusion import load_fusion_params
from ..estimation.vio_stream import VioStream
from ..estimation.visual_odometry import load_vo_params
from ..paths import config_path
from ..perception.camera_model import R_LINK_OPTICAL, CameraIntrinsics
from ..transforms import make_transform, matrix_to_quat, rot_z
from .camera import HeadCamera, LinkMount
from .depth_noise import DepthNoise
from .mjcf import camera_link_in_base
from .odometry_gate import GatedRemap
from .pose_sample import PoseSample
from .sensor_clock import SensorClock

D435I_FOCAL_PX_AT_640 = 615.0         # the colour stream's focal length at 640 px wide
#: the IMU's samples are fed from REST_FROM_S (s of simulated time): the plant drops onto the floor in
#: its first 40 ms (the specific force near zero, then a 30 m/s^2 jolt); the fusion levels its first pose
#: on the mean specific force before its first frame and calibrates the gyro on the rest window before
#: it: the first frame is LEVELLING_S plus that window after REST_FROM_S
REST_FROM_S, LEVELLING_S = 0.2, 0.1


@dataclass(frozen=True)
class OdometryCameraSettings:
    width: int = 320
    height: int = 240
    rate_hz: float = 10.0

    def problems(self) -> List[str]:
        out = []
        for key in ("width", "height"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, int) or not 16 <= v <= 1920:
                out.append(f"odometry camera {key}: must be an integer in [16, 1920] px, got {v!r}")
        v = self.rate_hz
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and 0 < v <= 100):
            out.append(f"odometry camera rate_hz: must be a number in (0, 100], got {v!r}")
        return out

    def intrinsics(self) -> CameraIntrinsics:
        f = D435I_FOCAL_PX_AT_640 * self.width / 640.0
        return CameraIntrinsics(self.width, self.height, f, f, self.width / 2.0, self.height / 2.0)


ODOMETRY_CAMERA = OdometryCameraSettings()


class OdometryCamera:
    """camera_link's colour + noisy depth frames on a grid of simulated time (see the module's docstring)."""

    def __init__(self, plant, camera_link_in_base_T, settings: OdometryCameraSettings, depth_model):
        problems = settings.problems()
        if problems:
            raise ValueError("; ".join(problems))
        self.settings = settings
        self.intrinsics = settings.intrinsics()
        self.camera = HeadCamera(plant.model, self.intrinsics, LinkMount(camera_link_in_base_T),
                                 depth_model=depth_model)
        self.clock = SensorClock(settings.rate_hz)
        self.render_s: List[float] = []       # wall time of each render (s)

    def poll(self, plant, blank: bool = False) -> Optional[Tuple[float, np.ndarray, np.ndarray]]:
        """(stamp, rgb, depth_m) when a frame fell due at plant.time_s, else None; blank: a black frame
        without depth (not rendered)."""
        if not self.clock.due(plant.time_s):
            return None
        self.clock.tick(plant.time_s)
        stamp = plant.imu_truth()[0]
        k = self.intrinsics
        if blank:
            return stamp, np.zeros((k.height, k.width, 3), np.uint8), np.zeros((k.height, k.width), np.float32)
        w0 = time.perf_counter()
        frame = self.camera.render(plant.data, plant.frame_transform("base_link"), stamp, labels=False)
        self.render_s.append(time.perf_counter() - w0)
        return stamp, frame.rgb, frame.depth_m

    def close(self) -> None:
        self.camera.close()


def odometry_anchor(T_world_link: np.ndarray) -> np.ndarray:
    """The odometry frame in the world: at camera_link's position, turned by its heading (the heading
    of its x axis on the level plane), level: where a fusion that starts level with zero yaw at
    that pose puts its origin (vio_fusion.level_pose)."""
    R = np.asarray(T_world_link, float)[:3, :3]
    return make_transform(rot_z(math.atan2(R[1, 0], R[0, 0])), np.asarray(T_world_link, float)[:3, 3])


class VoFeedback:
    """See the module's docstring."""
    name = "vo"

    def __init__(self, world, robot, camera: OdometryCameraSettings = ODOMETRY_CAMERA,
                 estimation_config: Optional[str] = None, blackouts: Sequence[Tuple[float, float]] = (),
                 start_s: Optional[float] = None):
        if world.imu is None:
            raise ValueError("feedback vo: the world samples no IMU (WorldSpec.sensors must hold 'imu')")
        params = world.params
        self.world, self.plant = world, world.plant
        self.remap = GatedRemap(params, robot)             # the gate and eq. 3.1
        self.gate = self.remap.gate
        path = estimation_config or str(config_path("estimation.yaml"))
        self.camera_in_head = world.camera_in_head
        link_in_base = camera_link_in_base(robot.head_length_m, self.camera_in_head)
        self.camera = OdometryCamera(self.plant, link_in_base, camera,
                                     DepthNoise(params.config.depth_noise, camera.intrinsics().fx,
                                                params.rng("depth_noise")))
        fusion = load_fusion_params(path)
        self.stream = VioStream(self.camera.intrinsics.K(), make_transform(R_LINK_OPTICAL), load_vo_params(path),
                                fusion, imu_wait_s=math.inf)
        self.blackouts = [(float(a), float(b)) for a, b in blackouts]
        self.start_s = REST_FROM_S + LEVELLING_S + fusion.rest_calibration_s if start_s is None else float(start_s)
        self.T_world_odom: Optional[np.ndarray] = None
        self.samples: List[tuple] = []
        self._truth = {}                       # frame stamp -> camera_link's true 4x4

    def pose(self, out):
        for s in list(out.imu_between) + ([out.imu] if out.imu is not None else []):
            if s.t_s >= REST_FROM_S:
                self.stream.add_imu(s.t_s, s.angular_velocity_rad_s, s.linear_acceleration_m_s2)
        if out.t_s < self.start_s - 1e-9:
            return None
        blank = any(a <= out.t_s < b for a, b in self.blackouts)
        frame = self.camera.poll(self.plant, blank=blank)
        if frame is not None:
            stamp, rgb, depth = frame
            self._truth[stamp] = self.plant.frame_transform("head_link") @ self.camera_in_head
            self.stream.add_colour(stamp, rgb)
            self.stream.add_depth(stamp, depth)
        result = self.stream.step()
        if result is None:
            return None
        truth = self._truth.pop(result.stamp)
        for t in [t for t in self._truth if t < result.stamp]:    # frames the stream dropped
            del self._truth[t]
        if self.T_world_odom is None:
            self.T_world_odom = odometry_anchor(truth)
        T = self.T_world_odom @ result.T_world_link
        R6 = np.kron(np.eye(2), self.T_world_odom[:3, :3])
        cov = R6 @ np.asarray(result.covariance, float) @ R6.T       # about the world's axes
        q = matrix_to_quat(T[:3, :3])
        self.samples.append((result.stamp, T[:3, 3].copy(), q, not result.ok, truth[:3, 3].copy(),
                             matrix_to_quat(truth[:3, :3])))
        base = self.remap.base_in_world(PoseSample(result.stamp, "camera_link", T[:3, 3], q, cov, not result.ok))
        if base is None:
            return None
        return result.stamp, base[:3, 3].copy(), matrix_to_quat(base[:3, :3])

    def status(self, t_s: float):
        return self.remap.status(t_s)

    def summary(self) -> dict:
        """The stream's figures (vio_node's diagnostics: frames, lost intervals and causes, ms per
        frame) plus the renders' wall time and the gate's refusals."""
        out = self.stream.stats.summary()
        last = self.samples[-1][0] if self.samples else 0.0      # an interval still open ends there
        out["lost_s_total"] = float(sum((last if end is None else end) - start
                                        for start, end in self.stream.stats.lost_intervals))
        r = np.array(self.camera.render_s) if self.camera.render_s else np.zeros(1)
        out.update({"render_ms_median": float(np.median(r) * 1e3), "render_s_total": float(r.sum()),
                    "gate_rejected": int(self.gate.rejected),
                    "camera": {"width": self.camera.settings.width, "height": self.camera.settings.height,
                               "rate_hz": self.camera.settings.rate_hz}})
        return out

    def close(self) -> None:
        self.camera.close()
