"""The driver's 100 Hz loop for lock-step (batch) runs, through the core's bindings.

The ROS path runs the C++ DriverController (src/core/driver_controller.cpp) in driver_node, talking
Protocol 2.0 to the mocked bus. Batch runs need the same behaviour without a bus and faster than
real time, so this class repeats the controller's cycle on the same core objects (CPG, GaitLibrary,
Steering, Kinematics from snake_autonomy._core):

    update(t_s, dt_s, q_measured_rad):
        base pose -> fresh? -> gate locomotion (stale pose: amplitudes to zero, ERRATA #7)
        -> CPG step -> goals slew-limited (max_joint_velocity_rad_s) and clamped to the joint limits
        -> forward kinematics on the measured joints: centre of mass, virtual chassis

Behaviour kept from DriverController: the first gait command restarts the oscillators at the held
posture (amplitudes zero, biases = posture) so the goals continue from where the robot is; later
commands only change the CPG targets (the critically damped dynamics smooth the change); a gait
command is resolved as GaitCommandResolver does (library gait, steering on the yaw amplitudes when
`steer`); com_pose exists only while the base pose is fresh. Not repeated: the bus (the plant is
driven directly), faults, torque requests.
"""
import math
from typing import Optional, Tuple

import numpy as np

from snake_autonomy import _core

HOLDING, RUNNING = "holding", "running"


class SimDriver:
    def __init__(self, robot, library, max_joint_velocity_rad_s: float = 4.5, pose_timeout_s: float = 0.5,
                 require_pose: bool = True, max_step_s: float = 0.05):
        self.robot = robot
        self.library = library
        self.steering = _core.Steering(robot)
        self.kinematics = _core.Kinematics(robot)
        self.cpg = _core.CPG(robot)
        self.max_joint_velocity_rad_s = float(max_joint_velocity_rad_s)
        self.pose_timeout_s = float(pose_timeout_s)
        self.require_pose = bool(require_pose)
        self.max_step_s = float(max_step_s)
        self.lower_rad = np.asarray(robot.joint_lower_rad, float)
        self.upper_rad = np.asarray(robot.joint_upper_rad, float)
        n = robot.num_joints
        self.state = HOLDING
        self.gait = ""
        self._pending = None              # (name, GaitParameters) handed over to the next update
        self._nominal = None
        self._gated = False
        self._hold = None                 # posture held (rad)
        self.goal_rad = None
        self._base: Optional[Tuple[np.ndarray, np.ndarray]] = None
        self._pose_t = None
        self.pose_fresh = False
        self.kin = None                   # the latest _core.KinematicState
        self.commands_applied = 0
        self.cpg_clamped = 0              # CPG outputs beyond a joint limit (the goal was clamped)
        self._zeros = np.zeros(n)

    # ---- inputs (any time) ---------------------------------------------------------------------
    def command_gait(self, gait: str, steer: bool = False, delta_rad: float = 0.0) -> str:
        """Resolves a gait command; '' when accepted, else why not (nothing changes then)."""
        if gait not in self.library:
            return f"gait: unknown gait {gait!r} (known: {', '.join(self.library.names)})"
        params = self.library.parameters(gait, self.robot)
        if steer:
            if not math.isfinite(delta_rad):
                return f"delta: {delta_rad} is not a finite number"
            if not self.library.steerable(gait):
                return f"steer: gait {gait!r} is not steerable"
            params.amplitude = self.steering.modify_amplitudes(params.amplitude, delta_rad)
        self._pending = (gait, params)
        return ""

    def set_base_pose(self, t_s: float, position, quat_xyzw) -> bool:
        p, q = np.asarray(position, float), np.asarray(quat_xyzw, float)
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(q))) or np.linalg.norm(q) < 1e-9:
            return False
        self._base = (p, q)
        self._pose_t = float(t_s)
        return True

    # ---- the cycle -----------------------------------------------------------------------------
    def update(self, t_s: float, dt_s: float, q_measured_rad) -> np.ndarray:
        """One cycle; returns the joint goals (rad) to write."""
        q = np.asarray(q_measured_rad, float)
        dt_s = min(max(dt_s, 0.0), self.max_step_s) if math.isfinite(dt_s) else 0.0
        if self._hold is None:                       # start(): hold the measured posture
            self._hold = np.clip(q, self.lower_rad, self.upper_rad)
            self.goal_rad = self._hold.copy()
        if self._pending is not None:
            self.gait, self._nominal = self._pending
            self._pending = None
            if self.state == HOLDING:
                self.cpg.reset(self.cpg.phases, self._zeros, self._hold)
                self.state = RUNNING
                self._gated = self.require_pose and not self._fresh(t_s)
            self._apply()
            self.commands_applied += 1
        self.pose_fresh = self._fresh(t_s)
        gate = self.require_pose and not self.pose_fresh
        if self.state == RUNNING and gate != self._gated:
            self._gated = gate
            self._apply()
        if self.state == RUNNING:
            target = np.asarray(self.cpg.step(dt_s)) if dt_s > 0 else np.asarray(self.cpg.output)
            raw = np.asarray(self.cpg.unclamped_output)
            self.cpg_clamped += int(np.count_nonzero((raw < self.lower_rad) | (raw > self.upper_rad)))
        else:
            target = self._hold
        max_move = self.max_joint_velocity_rad_s * dt_s
        self.goal_rad = np.clip(self.goal_rad + np.clip(target - self.goal_rad, -max_move, max_move),
                                self.lower_rad, self.upper_rad)
        if self._base is not None:
            self.kin = self.kinematics.compute(self._base[0], self._base[1], q)
        return self.goal_rad

    def com_pose(self) -> Optional[Tuple[float, float, float]]:
        """(x, y, yaw) of the centre of mass and virtual chassis, as com_pose carries it; None while
        the base pose is stale (the driver publishes com_pose only from a fresh one)."""
        if not self.pose_fresh or self.kin is None:
            return None
        R = np.asarray(self.kin.vc_rotation)
        com = np.asarray(self.kin.com)
        return float(com[0]), float(com[1]), math.atan2(R[1, 0], R[0, 0])

    # ---- internals -----------------------------------------------------------------------------
    def _fresh(self, t_s: float) -> bool:
        return self._pose_t is not None and t_s - self._pose_t <= self.pose_timeout_s

    def _apply(self) -> None:
        params = self._nominal
        if self._gated:
            gated = self.library.parameters(self.gait, self.robot)
            gated.omega, gated.phase, gated.bias = params.omega, params.phase, params.bias
            gated.amplitude = self._zeros
            params = gated
        self.cpg.apply(params)
