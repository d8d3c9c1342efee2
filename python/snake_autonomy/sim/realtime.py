"""The simulated robot in real time, behind the mocked servo bus: what sim_node wraps (ROS-free).

    sim = RealTimeSim(SimSetup(feedback="vio", port="/tmp/snake_sim_bus", seed=0))
    sim.start()                        # the pty answers Protocol 2.0 from now on (the C++ driver's port)
    out = sim.step(time.monotonic())   # physics up to now; the sensor samples that fell due

The physics advances with the bus's clock (time.monotonic): the mocked bus steps it before each
reply, step() whenever it is called (so sensors stay live while the driver is quiet). The plant,
sensors, start pose, tracker calibration and disturbance triggers are the batch runner's
(sim.batch, sim.disturbances): same config/sim.yaml, same classes, only the clock differs.
"""
import math
import threading
import time
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np

from snake_autonomy import _core

from ..control.angles import wrap
from ..estimation import load_camera_calibration
from ..missions import load_defaults, load_mission
from .batch import CONFIG, start_base_pose
from .config import SimConfig
from .disturbances import Disturbance, parse_triggers
from .mock_servo_bus import MockServoBus
from .mocap import MocapSensor
from .mujoco_servo_backend import MujocoServoBackend
from .plant import Plant
from .pose_sample import PoseSample
from ..transforms import matrix_to_quat
from .vio import SimulatedVio


@dataclass
class SimSetup:
    feedback: str = "mocap"                    # mocap | vio
    seed: int = 0
    start: Tuple[float, float, float] = (0.0, 0.0, 0.0)   # CoM x_m, y_m, heading_deg (as the batch runner)
    port: str = "/tmp/snake_sim_bus"
    control: Optional[str] = None              # control socket (default port + ".ctl")
    sim_config: str = str(CONFIG / "sim.yaml")
    robot: str = str(CONFIG / "robots" / "cobra.yaml")
    tracker_config: str = str(CONFIG / "tracker.yaml")
    mission: str = ""                          # for its disturbances (optional)


@dataclass
class StepOutput:
    t_s: float                                 # plant time
    mocap: Optional[PoseSample] = None         # base_link, noisy (the mocap feedback)
    vio: Optional[PoseSample] = None           # camera odometry (the vio feedback)
    truth_camera: Optional[Tuple[np.ndarray, np.ndarray]] = None   # with every vio sample
    truth_base: Optional[Tuple[np.ndarray, np.ndarray]] = None     # with every mocap sample
    fired: List[str] = field(default_factory=list)                 # disturbances applied now


class RealTimeSim:
    def __init__(self, setup: SimSetup):
        if setup.feedback not in ("mocap", "vio"):
            raise ValueError(f"feedback: expected mocap or vio, got {setup.feedback!r}")
        self.setup = setup
        self.config = SimConfig.from_yaml(setup.sim_config)
        self.defaults = load_defaults(setup.tracker_config, self.config.tracker,
                                      overrides_source=f"{setup.sim_config} (tracker:)")
        self.heading_offset_rad = math.radians(self.defaults["heading_offset_deg"])
        self.robot = _core.RobotModel.from_yaml(setup.robot)
        self.kinematics = _core.Kinematics(self.robot)
        self.params = self.config.draw(setup.seed, num_joints=self.robot.num_joints)
        start = start_base_pose(self.robot, self.kinematics, setup.start, self.heading_offset_rad)
        self.plant = Plant(self.robot, self.params, start=start)
        self.backend = MujocoServoBackend(self.plant)
        self.bus = MockServoBus(self.backend, list(self.robot.servo_ids))
        self.mocap = MocapSensor(self.params)
        self.vio = SimulatedVio(self.params, load_camera_calibration(self.config.calibration_path()).camera_in_head)
        self.mission = load_mission(setup.mission, defaults=self.defaults) if setup.mission else None
        self.triggers = parse_triggers(self.mission.raw.get("disturbances"), len(self.mission.waypoints)) \
            if self.mission else []
        self.target_index = 0
        self.mission_t0: Optional[float] = None     # plant time when the mission started
        self.rolled_over = False
        self.max_tilt_deg = 0.0
        self._lock = threading.Lock()
        self._pending: List[Disturbance] = []

    # ---- lifecycle -------------------------------------------------------------------------------
    def start(self):
        self.bus.start(self.setup.port, self.setup.control or f"{self.setup.port}.ctl")
        return self

    def stop(self):
        self.bus.stop()

    def wait_bus_idle(self, quiet_s: float = 0.3, timeout_s: float = 5.0, clock=time.monotonic) -> bool:
        """Keeps serving the bus until no packet arrived for quiet_s (the driver has stopped talking:
        its final shutdown write is in) or timeout_s passed; True when it went quiet. Call before
        stop() when everything shuts down at once (Ctrl+C of a launch): the driver's shutdown action
        needs the bus."""
        start = last_change = clock()
        last = self.bus.stats()["packets"]
        while clock() - start < timeout_s:
            time.sleep(0.02)
            now, packets = clock(), self.bus.stats()["packets"]
            if packets != last:
                last, last_change = packets, now
            elif now - last_change >= quiet_s:
                return True
        return False

    # ---- inputs ----------------------------------------------------------------------------------
    def set_target(self, waypoint_index: int) -> None:
        """The tracker's active waypoint (tracking_status): arms the mid-leg disturbance triggers."""
        with self._lock:
            if self.mission_t0 is None:
                self.mission_t0 = self.plant.time_s
            self.target_index = int(waypoint_index)

    def disturb(self, link: str, force_n=None, torque_nm=None, duration_s: float = 0.1) -> None:
        """A push or twist now (next physics step); ValueError for an unknown body."""
        with self._lock:
            self._pending.append(Disturbance(time_s=0.0, link=link, force_n=force_n, torque_nm=torque_nm,
                                             duration_s=duration_s))

    # ---- the step --------------------------------------------------------------------------------
    def step(self, now_s: float) -> StepOutput:
        plant = self.plant
        with self.backend.lock:
            self.backend.advance_locked(now_s)
            out = StepOutput(plant.time_s)
            for d in self._take_pending():
                plant.add_disturbance(Disturbance(plant.time_s + plant.dt_s, d.link, d.force_n, d.torque_nm,
                                                  d.duration_s))
                out.fired.append(f"{d.link}: force {d.force_n} N, torque {d.torque_nm} N m for {d.duration_s} s")
            if self.mocap.clock.due(plant.time_s):
                world_t_base = plant.frame_transform("base_link")
                out.mocap = self.mocap.measure(plant.time_s, world_t_base)
                out.truth_base = (world_t_base[:3, 3].copy(), matrix_to_quat(world_t_base[:3, :3]))
            if self.setup.feedback == "vio" and self.vio.clock.due(plant.time_s):
                world_t_head = plant.frame_transform("head_link")
                out.vio = self.vio.measure(plant.time_s, world_t_head)
                cam = world_t_head @ self.vio.head_t_camera
                out.truth_camera = (cam[:3, 3].copy(), matrix_to_quat(cam[:3, :3]))
            tilt = plant.base_tilt_deg()
            self.max_tilt_deg = max(self.max_tilt_deg, tilt)
            if tilt > self.config.monitor.rollover_tilt_deg:
                self.rolled_over = True
            out.fired += self._check_triggers()
        return out

    def true_com_pose(self) -> Tuple[float, float, float]:
        """Centre of mass and heading (direction of travel) from the true base pose (lock held)."""
        p, q = self.plant.frame_pose("base_link")
        s = self.kinematics.compute(p, q, self.plant.joint_positions_rad())
        R = np.asarray(s.vc_rotation)
        return float(s.com[0]), float(s.com[1]), wrap(math.atan2(R[1, 0], R[0, 0]) + self.heading_offset_rad)

    def _take_pending(self):
        with self._lock:
            out, self._pending = self._pending, []
        return out

    def _check_triggers(self) -> List[str]:
        if not self.triggers or self.mission_t0 is None:
            return []
        x, y, _ = self.true_com_pose()
        wps = self.mission.waypoints
        k = min(self.target_index, len(wps) - 1)
        d = math.hypot(wps[k][0] - x, wps[k][1] - y)
        fired = []
        for trig in list(self.triggers):
            if trig.due(self.plant.time_s - self.mission_t0, self.target_index, d):
                self.triggers.remove(trig)
                self.plant.add_disturbance(trig.at(self.plant.time_s + self.plant.dt_s))
                fired.append(trig.describe())
        return fired

    def status(self) -> dict:
        return {"sim_time_s": self.plant.time_s, "paused_s": self.backend.paused_s,
                "max_tilt_deg": self.max_tilt_deg, "rolled_over": self.rolled_over,
                "limit_violations": self.plant.limit_violations, "seed": self.setup.seed,
                "feedback": self.setup.feedback}
