"""One simulated world: plant + sensors + disturbances + monitor + ground truth, stepped by both
run paths (sim.batch in lock-step, sim.realtime behind the mocked bus): only the clock and the
transport differ.

    world = SimWorld(WorldSpec(seed=3, feedback="vio", start=(0.0, 0.0, 0.0), mission="star"))
    out = world.step_to(t_s)       # lock-step; real time: with world.lock: advance the backend, observe()
    out.mocap, out.vio             # PoseSamples that fell due, with out.truth_base / out.truth_camera
    world.true_com_pose()          # CoM and heading (direction of travel) from the true state

Sensors (motion capture 100 Hz, simulated RTAB-Map 30 Hz, with "imu" in spec.sensors the head
camera's IMU at sim.yaml imu.rate_hz) sample on their grids of simulated time; step_to stops the
physics at the IMU's sample times between two calls (out.imu_between). Feedback vo needs the IMU
only (FEEDBACK_SENSORS): its camera frames are rendered by the pose source (sim/vo_feedback.py).
A mission's triggers are checked at 10 Hz once it started (start_mission / set_target) and, like
pushes on command (disturb()), act from the next physics step; each fired trigger keeps the true
CoM pose then and 2 s later. The monitor: roll-over (monitor.rollover_tilt_deg), largest tilt,
joint goals beyond the limits. The start pose and true heading use the tracker's heading offset
(config/sim.yaml `tracker:` over config/tracker.yaml); scene_xml adds MJCF obstacles (Plant).
"""
import math
import threading
from dataclasses import dataclass, field
from typing import List, Optional, Sequence, Tuple

import numpy as np

from snake_autonomy import _core

from ..control.angles import wrap
from ..estimation import load_camera_calibration
from ..missions import load_defaults, load_mission
from ..paths import config_path
from ..transforms import matrix_to_quat
from .config import SimConfig
from .disturbances import Disturbance, parse_triggers
from .imu import ImuSample, ImuSensor
from .mocap import MocapSensor
from .mujoco_servo_backend import MujocoServoBackend
from .plant import Plant
from .pose_sample import PoseSample
from .sensor_clock import SensorClock
from .vio import SimulatedVio

CONFIG = config_path()
FEEDBACKS = ("mocap", "vio", "vo")
SENSORS = ("mocap", "vio", "imu")
#: the sensors each pose source needs (vo: the visual-inertial odometry on the head camera's frames,
#: sim/vo_feedback.py, renders its frames itself and reads the IMU)
FEEDBACK_SENSORS = {"mocap": ("mocap",), "vio": ("vio",), "vo": ("imu",)}
TRIGGER_CHECK_HZ = 10.0          # mission triggers checked on this grid of simulated time
RECOVERY_WINDOW_S = 2.0          # a fired trigger's CoM pose is recorded again this much later


@dataclass
class WorldSpec:
    seed: int = 0
    feedback: str = "mocap"                    # mocap | vio | vo: the pose source the run uses
    start: Tuple[float, float, float] = (0.0, 0.0, 0.0)   # CoM x_m, y_m, heading_deg of a straight body
    mission: str = ""                          # a file or a provided mission's name ("" none)
    sim_config: str = str(CONFIG / "sim.yaml")
    robot: str = str(CONFIG / "robots" / "cobra.yaml")
    tracker_config: str = str(CONFIG / "tracker.yaml")
    randomize: bool = True                     # per-seed physics (False: the ranges' midpoints)
    scene_xml: str = ""                        # MJCF elements added to the world (Plant, build_mjcf)
    assets_xml: str = ""                       # the textures and materials scene_xml uses
    start_base: Optional[Tuple[float, float, float]] = None   # base_link x_m, y_m, heading_rad on the
                                               # floor (a nav world file's start); None: from start
    flat_belly_fraction: Optional[float] = None   # plant option over sim_config's (nav runs: nav.yaml)
    sensors: Optional[Sequence[str]] = None    # sampled sensors (SENSORS); None: motion capture and the
                                               # feedback's; "imu" adds the IMU to the plant's model


@dataclass
class WorldStep:
    t_s: float                                                     # plant time
    mocap: Optional[PoseSample] = None                             # base_link, noisy
    vio: Optional[PoseSample] = None                               # camera odometry
    truth_base: Optional[Tuple[np.ndarray, np.ndarray]] = None     # with every mocap sample
    truth_camera: Optional[Tuple[np.ndarray, np.ndarray]] = None   # with every vio sample
    imu: Optional[ImuSample] = None                                # the head camera's IMU (camera_link)
    imu_between: List[ImuSample] = field(default_factory=list)     # step_to: its samples on the way, before imu
    fired: List[str] = field(default_factory=list)                 # disturbances applied now
    tilt_deg: float = 0.0                                          # base_link from the vertical


@dataclass
class FiredTrigger:
    description: str
    t_s: float                                  # plant time when it fired
    mission_t_s: float                          # seconds after the mission start
    target_index: int                           # the waypoint the robot was heading for
    com_before: Tuple[float, float, float]      # true CoM x, y, heading then
    com_after: Optional[Tuple[float, float, float]] = None   # RECOVERY_WINDOW_S later


def start_base_pose(robot, kinematics, start_xy_heading: Sequence[float], heading_offset_rad: float):
    """base_link (x, y, yaw) that puts a straight body's centre of mass at (x, y) with the tracker's
    heading `heading_deg` (virtual chassis yaw = heading - offset)."""
    x, y, heading_deg = (float(v) for v in start_xy_heading)
    yaw = math.radians(heading_deg) - heading_offset_rad
    q = np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)])
    state = kinematics.compute(np.zeros(3), q, np.zeros(robot.num_joints))
    com = np.asarray(state.com)
    return x - com[0], y - com[1], yaw


class SimWorld:
    def __init__(self, spec: WorldSpec, robot=None, gait_names: Optional[Sequence[str]] = None):
        """robot: a _core.RobotModel (None: read spec.robot); gait_names: the gait library's names,
        to check the mission's gaits (None: not checked)."""
        if spec.feedback not in FEEDBACKS:
            raise ValueError(f"feedback: expected one of {', '.join(FEEDBACKS)}, got {spec.feedback!r}")
        sensors = (tuple(spec.sensors) if spec.sensors is not None
                   else tuple({"mocap", *FEEDBACK_SENSORS[spec.feedback]}))
        unknown = sorted(set(sensors) - set(SENSORS))
        if unknown:
            raise ValueError(f"sensors: unknown {unknown}; known: {', '.join(SENSORS)}")
        self.spec = spec
        self.config = SimConfig.from_yaml(spec.sim_config)
        if spec.flat_belly_fraction is not None:
            self.config = self.config.with_flat_belly(spec.flat_belly_fraction)
        self.defaults = load_defaults(spec.tracker_config, self.config.tracker,
                                      overrides_source=f"{spec.sim_config} (tracker:)")
        self.heading_offset_rad = math.radians(self.defaults["heading_offset_deg"])
        self.robot = robot or _core.RobotModel.from_yaml(spec.robot)
        self.kinematics = _core.Kinematics(self.robot)
        self.params = self.config.draw(spec.seed, randomize=spec.randomize, num_joints=self.robot.num_joints)
        self.mission = (load_mission(spec.mission, defaults=self.defaults, gait_library=gait_names)
                        if spec.mission else None)
        self.triggers = (parse_triggers(self.mission.raw.get("disturbances"), len(self.mission.waypoints))
                         if self.mission else [])         # all of the mission's (fired or not)
        start = (tuple(spec.start_base) if spec.start_base is not None else
                 start_base_pose(self.robot, self.kinematics, spec.start, self.heading_offset_rad))
        camera_in_head = (load_camera_calibration(self.config.calibration_path()).camera_in_head
                          if {"vio", "imu"} & set(sensors) else None)
        self.camera_in_head = camera_in_head    # camera_link in head_link (config/camera.yaml), or None
        self.plant = Plant(self.robot, self.params, start=start, scene_xml=spec.scene_xml,
                           assets_xml=spec.assets_xml, imu_in_head=camera_in_head if "imu" in sensors else None)
        self.backend = MujocoServoBackend(self.plant)
        self.mocap = MocapSensor(self.params) if "mocap" in sensors else None
        self.vio = SimulatedVio(self.params, camera_in_head) if "vio" in sensors else None
        self.imu = (ImuSensor(self.config.imu, self.params.rng("imu"), step_s=self.plant.dt_s)
                    if "imu" in sensors else None)
        self.rollover_tilt_deg = self.config.monitor.rollover_tilt_deg
        self.rolled_over = False
        self._tilt_ref = None          # (frame, its world rotation) while the head is raised on purpose
        self.max_tilt_deg = 0.0
        self.mission_t0: Optional[float] = None     # plant time when the mission started
        self.target_index = 0
        self.fired: List[FiredTrigger] = []
        self._armed = list(self.triggers)
        self._trigger_clock = SensorClock(TRIGGER_CHECK_HZ)
        self._inputs = threading.Lock()              # set_target / disturb may come from other threads
        self._pending: List[Disturbance] = []

    @property
    def lock(self) -> threading.Lock:
        """Held while the plant is stepped or read (the mocked bus steps it from its own thread)."""
        return self.backend.lock

    @property
    def limit_violations(self) -> int:
        return int(self.plant.limit_violations)

    # ---- inputs ----------------------------------------------------------------------------------
    def start_mission(self, t_s: float) -> None:
        """The mission starts (or started) at plant time t_s: its triggers are armed from then on."""
        with self._inputs:
            self.mission_t0 = float(t_s)

    def set_target(self, waypoint_index: int) -> None:
        """The tracker's active waypoint (arms the mid-leg triggers); the first call starts the
        mission if start_mission was not called."""
        with self._inputs:
            if self.mission_t0 is None:
                self.mission_t0 = self.plant.time_s
            self.target_index = int(waypoint_index)

    def disturb(self, link: str, force_n=None, torque_nm=None, duration_s: float = 0.1) -> None:
        """A push or twist from the next physics step; ValueError for an unknown body."""
        self.plant._body_id(link)
        with self._inputs:
            self._pending.append(Disturbance(time_s=0.0, link=link, force_n=force_n, torque_nm=torque_nm,
                                             duration_s=duration_s))

    # ---- the step --------------------------------------------------------------------------------
    def step_to(self, t_s: float) -> WorldStep:
        """Lock-step: the physics to t_s, then observe(). With the IMU on, the physics stops at each of
        its sample times on the way (200 Hz against a 100 Hz caller): those samples are out.imu_between."""
        between = []
        if self.imu is not None:
            between = self.imu.step_plant_to(self.plant, t_s)     # ends at t_s
        else:
            self.plant.step_to(t_s)
        out = self.observe()
        out.imu_between = between
        return out

    def observe(self) -> WorldStep:
        """The world at the plant's present time: pushes on command applied, the sensors that fell
        due sampled, the monitor updated, the mission's triggers checked. Call with `lock` held when
        another thread may step the plant."""
        plant = self.plant
        t = plant.time_s
        out = WorldStep(t)
        with self._inputs:
            pending, self._pending = self._pending, []
        for d in pending:
            plant.add_disturbance(Disturbance(t + plant.dt_s, d.link, d.force_n, d.torque_nm, d.duration_s))
            out.fired.append(f"{d.link}: force {d.force_n} N, torque {d.torque_nm} N m for {d.duration_s} s")
        if self.mocap is not None and self.mocap.clock.due(t):
            world_t_base = plant.frame_transform("base_link")
            out.mocap = self.mocap.measure(t, world_t_base)
            out.truth_base = (world_t_base[:3, 3].copy(), matrix_to_quat(world_t_base[:3, :3]))
        if self.vio is not None and self.vio.clock.due(t):
            world_t_head = plant.frame_transform("head_link")
            out.vio = self.vio.measure(t, world_t_head)
            cam = world_t_head @ self.vio.head_t_camera
            out.truth_camera = (cam[:3, 3].copy(), matrix_to_quat(cam[:3, :3]))
        if self.imu is not None:
            out.imu = self.imu.poll(plant)
        out.tilt_deg = plant.base_tilt_deg() if self._tilt_ref is None else self._reference_tilt_deg()
        self.max_tilt_deg = max(self.max_tilt_deg, out.tilt_deg)
        if out.tilt_deg > self.rollover_tilt_deg:
            self.rolled_over = True
        out.fired += self._check_triggers(t)
        for f in self.fired:
            if f.com_after is None and t >= f.t_s + RECOVERY_WINDOW_S - 1e-9:
                f.com_after = self.true_com_pose()
        return out

    # ---- ground truth ----------------------------------------------------------------------------
    def watch_tilt_of(self, frame: Optional[str]) -> None:
        """While a scout stop raises the head (base_link) on purpose, the roll-over check watches
        `frame` (a frame of the lying base, e.g. the tail) tipping from its present orientation
        instead of base_link's tilt from the vertical; None goes back to base_link."""
        self._tilt_ref = None if frame is None else (frame, self.plant.frame_transform(frame)[:3, :3].copy())

    def watch_tail(self, on: bool) -> None:
        """While a scout trajectory raises the head on purpose (both run paths say when), the roll-over
        check watches the tail's tilt from where it lay (watch_tilt_of); idempotent: the reference is
        taken once, when watching starts."""
        if bool(on) != (self._tilt_ref is not None):
            self.watch_tilt_of(self.robot.frame_names[-1] if on else None)

    def _reference_tilt_deg(self) -> float:
        frame, rot0 = self._tilt_ref
        up = self.plant.frame_transform(frame)[:3, :3] @ rot0.T[:, 2]
        return float(np.degrees(np.arccos(np.clip(up[2], -1.0, 1.0))))

    def true_com_pose(self) -> Tuple[float, float, float]:
        """Centre of mass (x, y) and heading (virtual chassis yaw + heading offset) from the true
        base pose and joint angles: what the driver would compute from a perfect pose."""
        p, q = self.plant.frame_pose("base_link")
        s = self.kinematics.compute(p, q, self.plant.joint_positions_rad())
        R = np.asarray(s.vc_rotation)
        return float(s.com[0]), float(s.com[1]), wrap(math.atan2(R[1, 0], R[0, 0]) + self.heading_offset_rad)

    def status(self) -> dict:
        return {"sim_time_s": self.plant.time_s, "max_tilt_deg": self.max_tilt_deg,
                "rolled_over": self.rolled_over, "limit_violations": self.limit_violations,
                "seed": self.spec.seed, "feedback": self.spec.feedback}

    # ---- internals -------------------------------------------------------------------------------
    def _check_triggers(self, t: float) -> List[str]:
        with self._inputs:
            t0, target = self.mission_t0, self.target_index
        if not self._armed or t0 is None or t < t0 - 1e-9 or not self._trigger_clock.due(t):
            return []
        self._trigger_clock.tick(t)
        x, y, heading = self.true_com_pose()
        wps = self.mission.waypoints
        wp = wps[min(target, len(wps) - 1)]
        d = math.hypot(wp[0] - x, wp[1] - y)
        fired = []
        for trig in list(self._armed):
            if trig.due(t - t0, target, d):
                self._armed.remove(trig)
                self.plant.add_disturbance(trig.at(t + self.plant.dt_s))
                self.fired.append(FiredTrigger(trig.describe(), t, t - t0, target, (x, y, heading)))
                fired.append(trig.describe())
        return fired
