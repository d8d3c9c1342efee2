"""The physics plant: the simulated robot in MuJoCo, in joint units, stepped to a requested time.

    robot = _core.RobotModel.from_yaml("config/robots/cobra.yaml")
    params = SimConfig.from_yaml("config/sim.yaml").draw(seed=3)
    plant = Plant(robot, params, start=(0.0, 0.0, 0.0))
    plant.set_joint_targets(q_rad)        # clamped to the joint limits, never beyond
    plant.step_to(t_s)                    # deterministic: same params + same calls = same states
    p, quat_xyzw = plant.frame_pose("base_link")

Joint angles are the thesis's q (eq. 3.4), not servo shaft angles (see mujoco_servo_backend).

The servos: each joint's goal is reached through a setpoint that moves toward it no faster than
servo.speed_limit_rad_s (re-aimed on a fixed grid of servo.setpoint_period_s and whenever a goal
changes), stays within the joint limits (MuJoCo actrange), and drives a PD whose torque saturates at
servo.torque_limit_nm (MuJoCo forcerange). Torque off sets that joint's gains to zero: the joint is
limp but for the gear train's damping and dry friction. Turning torque back on holds the present
position first (the setpoint restarts from the measured angle).
"""
import math
from typing import Optional, Sequence

import mujoco
import numpy as np

from .config import SimParams
from .disturbances import Disturbance, DisturbanceSchedule
from .mjcf import IMU_SENSORS, build_mjcf
from ..transforms import matrix_to_quat, make_transform


#: A goal further than this beyond a joint limit counts as a limit violation (about one servo tick:
#: goals that went through the bus are rounded to ticks).
LIMIT_TOLERANCE_RAD = 0.002


class Plant:
    def __init__(self, robot, params: SimParams, start=(0.0, 0.0, 0.0),
                 q0_rad: Optional[Sequence[float]] = None, disturbances=None, scene_xml: str = "",
                 assets_xml: str = "", imu_in_head: Optional[np.ndarray] = None):
        """robot: a _core.RobotModel; start: (x_m, y_m, heading_rad) of base_link on the floor.

        disturbances: Disturbance items (or None for those of params.config).
        scene_xml: MJCF elements added to the world (obstacles, pipes; see build_mjcf);
        assets_xml: the textures and materials they use;
        imu_in_head: the head camera's IMU, its 4x4 pose in head_link (build_mjcf; imu_truth())."""
        self.robot = robot
        self.params = params
        self.num_joints = robot.num_joints
        self.frame_names = list(robot.frame_names)
        self.mjcf = build_mjcf(robot, params, scene_xml, assets_xml, imu_in_head)
        self.model = mujoco.MjModel.from_xml_string(self.mjcf)
        self.data = mujoco.MjData(self.model)
        self.dt_s = float(self.model.opt.timestep)
        self.lower_rad = np.asarray(robot.joint_lower_rad, float)
        self.upper_rad = np.asarray(robot.joint_upper_rad, float)
        servo = params.config.servo
        self.speed_limit_rad_s = servo.speed_limit_rad_s
        self.torque_limit_nm = servo.torque_limit_nm
        self._setpoint_steps = max(1, int(round(servo.setpoint_period_s / self.dt_s)))
        self._kp = np.asarray(params.kp_nm_per_rad, float).copy()
        self._kv = np.asarray(params.kv_nm_s_per_rad, float).copy()

        jnt, site = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_SITE
        joint_ids = [mujoco.mj_name2id(self.model, jnt, j) for j in robot.joint_names]
        self._qadr = np.array([self.model.jnt_qposadr[j] for j in joint_ids])
        self._dadr = np.array([self.model.jnt_dofadr[j] for j in joint_ids])
        self._site_ids = {f: mujoco.mj_name2id(self.model, site, f) for f in self.frame_names}
        self._body_ids = {self.model.body(i).name: i for i in range(1, self.model.nbody)}
        self._imu_adr = ([int(self.model.sensor_adr[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SENSOR, n)])
                          for n in IMU_SENSORS] if imu_in_head is not None else None)

        self._steps = 0
        self._sensed_step = 0              # the step whose state MuJoCo's sensors last read
        # the accelerometer's readings summed over the physics steps since imu_accel_mean() last ran
        self._accel_sum, self._accel_n = np.zeros(3), 0
        self.limit_violations = 0          # goals received beyond a joint limit (then clamped)
        self._goal = np.zeros(self.num_joints)
        self._torque_on = np.ones(self.num_joints, dtype=bool)
        self._reaim = True
        if disturbances is None:
            disturbances = params.config.disturbances
        self.disturbances = DisturbanceSchedule(disturbances)
        for name in self.disturbances.links():
            self._body_id(name)

        x, y, heading = start
        self.data.qpos[0:2] = (x, y)
        self.data.qpos[3:7] = (math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2))
        q0 = np.zeros(self.num_joints) if q0_rad is None else self.clamp(q0_rad)
        self.data.qpos[self._qadr] = q0
        self.data.act[:] = q0
        self._goal[:] = q0
        mujoco.mj_forward(self.model, self.data)

    # ---- time ----------------------------------------------------------------------------------
    @property
    def time_s(self) -> float:
        return self._steps * self.dt_s

    def step_to(self, t_s: float) -> None:
        """Advance the physics to t_s (rounded down to whole steps); earlier times do nothing."""
        target = int(math.floor(t_s / self.dt_s + 1e-9))
        while self._steps < target:
            grid_end = (self._steps // self._setpoint_steps + 1) * self._setpoint_steps
            if self._reaim or self._steps % self._setpoint_steps == 0:
                self._aim_setpoints((grid_end - self._steps) * self.dt_s)
            event = self.disturbances.next_event_after(self.time_s)
            event_step = (int(math.ceil(event / self.dt_s - 1e-9)) if math.isfinite(event)
                          else target)
            end = min(target, grid_end, max(event_step, self._steps + 1))
            self._apply_disturbances()
            if self._imu_adr is None:
                mujoco.mj_step(self.model, self.data, nstep=end - self._steps)
            else:                          # one step at a time: every step's specific force is summed
                a = self._imu_adr[1]
                for _ in range(end - self._steps):
                    mujoco.mj_step(self.model, self.data)
                    self._accel_sum += self.data.sensordata[a:a + 3]
                self._accel_n += end - self._steps
            self._steps = end
            self._sensed_step = end - 1    # mj_step reads the sensors before it integrates

    def step(self, duration_s: float) -> None:
        self.step_to(self.time_s + duration_s)

    # ---- commands ------------------------------------------------------------------------------
    def clamp(self, q_rad) -> np.ndarray:
        return np.clip(np.asarray(q_rad, float), self.lower_rad, self.upper_rad)

    def set_joint_targets(self, q_rad: Sequence[float]) -> None:
        """Goal angles of every joint (rad); values beyond the joint limits are clamped to them (and
        counted in limit_violations: the driver must never send one)."""
        q = np.asarray(q_rad, float)
        if q.shape != (self.num_joints,) or not np.all(np.isfinite(q)):
            raise ValueError(f"joint targets: expected {self.num_joints} finite values, "
                             f"got {q_rad}")
        self.limit_violations += int(np.count_nonzero((q < self.lower_rad - LIMIT_TOLERANCE_RAD)
                                                      | (q > self.upper_rad + LIMIT_TOLERANCE_RAD)))
        self._goal[:] = self.clamp(q)
        self._reaim = True

    def set_joint_target(self, joint_index: int, q_rad: float) -> None:
        if not math.isfinite(q_rad):
            raise ValueError(f"joint {joint_index + 1}: target must be finite, got {q_rad}")
        if not (self.lower_rad[joint_index] - LIMIT_TOLERANCE_RAD <= q_rad
                <= self.upper_rad[joint_index] + LIMIT_TOLERANCE_RAD):
            self.limit_violations += 1
        self._goal[joint_index] = min(max(q_rad, self.lower_rad[joint_index]),
                                      self.upper_rad[joint_index])
        self._reaim = True

    def set_torque(self, joint_index: int, enabled: bool) -> None:
        """Torque on: the servo holds the measured angle, then moves to its goal. Off: limp."""
        enabled = bool(enabled)
        if enabled == self._torque_on[joint_index]:
            return
        self._torque_on[joint_index] = enabled
        kp = self._kp[joint_index] if enabled else 0.0
        kv = self._kv[joint_index] if enabled else 0.0
        self.model.actuator_gainprm[joint_index, 0] = kp
        self.model.actuator_biasprm[joint_index, 1] = -kp
        self.model.actuator_biasprm[joint_index, 2] = -kv
        q = self.data.qpos[self._qadr[joint_index]]
        self.data.act[joint_index] = min(max(q, self.lower_rad[joint_index]),
                                         self.upper_rad[joint_index])
        self._reaim = True

    def torque_enabled(self, joint_index: int) -> bool:
        return bool(self._torque_on[joint_index])

    def add_disturbance(self, disturbance: Disturbance) -> None:
        self._body_id(disturbance.link)
        self.disturbances.add(disturbance)

    # ---- state ---------------------------------------------------------------------------------
    def joint_positions_rad(self) -> np.ndarray:
        return self.data.qpos[self._qadr].copy()

    def joint_velocities_rad_s(self) -> np.ndarray:
        return self.data.qvel[self._dadr].copy()

    def joint_state(self, joint_index: int):
        """(angle rad, velocity rad/s, servo torque N m) of one joint."""
        return (float(self.data.qpos[self._qadr[joint_index]]),
                float(self.data.qvel[self._dadr[joint_index]]),
                float(self.data.actuator_force[joint_index]))

    def joint_goals_rad(self) -> np.ndarray:
        return self._goal.copy()

    def setpoints_rad(self) -> np.ndarray:
        """The servos' present setpoints (speed-limited toward the goals; within the limits)."""
        return self.data.act.copy()

    def actuator_torques_nm(self) -> np.ndarray:
        """Torque each servo applies to its joint (N m, + increases q), after saturation."""
        return self.data.actuator_force.copy()

    def frame_transform(self, frame: str) -> np.ndarray:
        """4x4 world pose of a kinematic frame (base_link, head_link, link_1 ... link_N)."""
        sid = self._site_ids[frame]
        return make_transform(self.data.site_xmat[sid].reshape(3, 3), self.data.site_xpos[sid])

    def frame_pose(self, frame: str):
        """(position (3,), quaternion xyzw (4,)) of a kinematic frame in the world."""
        t = self.frame_transform(frame)
        return t[:3, 3].copy(), matrix_to_quat(t[:3, :3])

    def frame_positions(self) -> np.ndarray:
        """(num_frames, 3) world positions of every kinematic frame, in frame_names order."""
        return np.array([self.data.site_xpos[self._site_ids[f]] for f in self.frame_names])

    def imu_truth(self):
        """(t_s, angular velocity rad/s, specific force m/s^2): the IMU's true readings in its site's
        frame, as MuJoCo computed them in the last forward pass, and the time of that state (one
        physics step before time_s after a step: mj_step reads its sensors before integrating)."""
        if self._imu_adr is None:
            raise ValueError("imu_truth: this plant has no IMU (Plant(imu_in_head=...))")
        g, a = self._imu_adr
        return (self._sensed_step * self.dt_s, self.data.sensordata[g:g + 3].copy(),
                self.data.sensordata[a:a + 3].copy())

    def imu_accel_mean(self) -> np.ndarray:
        """The mean specific force (m/s^2, the IMU's frame) over the physics steps since the last call,
        and starts a new sum; with no step since then, the last forward pass's reading."""
        if self._imu_adr is None:
            raise ValueError("imu_accel_mean: this plant has no IMU (Plant(imu_in_head=...))")
        if self._accel_n == 0:
            return self.imu_truth()[2]
        mean = self._accel_sum / self._accel_n
        self._accel_sum, self._accel_n = np.zeros(3), 0
        return mean

    def center_of_mass(self) -> np.ndarray:
        return self.data.subtree_com[self._body_ids["base_link"]].copy()

    def base_tilt_deg(self) -> float:
        """Angle between base_link's z axis and the world's up (0 flat, > 90 upside down)."""
        z = self.data.site_xmat[self._site_ids["base_link"]].reshape(3, 3)[:, 2]
        return float(np.degrees(np.arccos(np.clip(z[2], -1.0, 1.0))))

    def base_velocity(self) -> np.ndarray:
        """Linear velocity (world frame, m/s) of base_link."""
        return self.data.qvel[0:3].copy()

    def set_configuration(self, q_rad: Sequence[float], base=None) -> None:
        """Place the robot kinematically (tests, resets): joints, goals, setpoints and optionally
        the base pose as a 4x4 world transform; velocities zeroed, time unchanged."""
        q = self.clamp(q_rad)
        self.data.qpos[self._qadr] = q
        self.data.act[:] = q
        self._goal[:] = q
        if base is not None:
            self.data.qpos[0:3] = base[:3, 3]
            self.data.qpos[3:7] = np.roll(matrix_to_quat(base[:3, :3]), 1)
        self.data.qvel[:] = 0
        mujoco.mj_forward(self.model, self.data)
        self._sensed_step = self._steps

    # ---- internals -----------------------------------------------------------------------------
    def _aim_setpoints(self, horizon_s: float) -> None:
        """Velocity commands that bring each setpoint to its goal within horizon_s if the speed
        limit allows; limp joints keep their setpoint on the measured angle."""
        act = self.data.act
        v = np.clip((self._goal - act) / horizon_s, -self.speed_limit_rad_s,
                    self.speed_limit_rad_s)
        limp = ~self._torque_on
        if limp.any():
            act[limp] = np.clip(self.data.qpos[self._qadr[limp]], self.lower_rad[limp],
                                self.upper_rad[limp])
            v[limp] = 0.0
        self.data.ctrl[:] = v
        self._reaim = False

    def _apply_disturbances(self) -> None:
        xfrc = self.data.xfrc_applied
        if not self.disturbances.items:
            return
        xfrc[:] = 0.0
        for d in self.disturbances.active(self.time_s + 0.5 * self.dt_s):
            xfrc[self._body_id(d.link)] += d.wrench()

    def _body_id(self, name: str) -> int:
        try:
            return self._body_ids[name]
        except KeyError:
            raise ValueError(f"disturbance link {name!r}: no such body (expected one of "
                             f"{', '.join(self._body_ids)})") from None

