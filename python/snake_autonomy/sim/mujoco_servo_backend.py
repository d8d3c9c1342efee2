"""The MuJoCo plant behind the mocked servo bus: ServoBackend in servo units, by Dynamixel ID.

Servo shaft angle (rad from the servo's centre tick) and joint angle q (eq. 3.4) are related by the
robot YAML's servo direction d (+1/-1) and zero offset z (ticks at q = 0, from the centre), with the
control table's resolution: the C++ Transmission (_core.Transmission, the only place that converts)

    ticks = centre + z + d * q / rad_per_tick   <=>   shaft_rad = z * rad_per_tick + d * q

Present Current is the servo's torque over servo.torque_constant_nm_per_a (2.25 N m/A assumed:
the XH540-W270's 9.9 N m stall torque at 4.4 A stall current, gearbox included; no-load current
ignored), in the shaft's direction.

Time: `advance(now_s)` takes the bus's monotonic clock. The first call pins that clock to the
plant's present time; later calls step the physics by the elapsed time. A gap longer than
max_catch_up_s (the process was paused, a debugger stopped it) is not simulated in one go: the
world is taken to have paused too, the excess is added to `paused_s`, and the physics advances by
max_catch_up_s. For lock-step use (batch runs), pass the simulation time itself as now_s.
Thread-safe: the mocked bus may call from its own thread.
"""
import threading

from snake_autonomy import _core
from snake_autonomy.paths import config_path

from .plant import Plant
from .servo_backend import ServoBackend, ShaftState


class MujocoServoBackend(ServoBackend):
    def __init__(self, plant: Plant, max_catch_up_s: float = 1.0, table=None):
        """table: the servos' _core.dynamixel.ControlTable (default config/dynamixel/<servo model>.yaml)."""
        self.plant = plant
        robot = plant.robot
        self.max_catch_up_s = max_catch_up_s
        self.torque_constant_nm_per_a = plant.params.config.servo.torque_constant_nm_per_a
        self._index = {int(sid): i for i, sid in enumerate(robot.servo_ids)}
        if table is None:
            table = _core.dynamixel.ControlTable.from_yaml(str(config_path("dynamixel", f"{robot.servo_model}.yaml")))
        self.transmissions = _core.Transmission.for_robot(robot, table)
        self._direction = [float(t.direction) for t in self.transmissions]
        self._clock_offset_s = None        # plant time = now_s - offset
        self.paused_s = 0.0
        self._lock = threading.Lock()

    @property
    def lock(self) -> threading.Lock:
        """Held while the plant is stepped or read: take it to read the plant from another thread."""
        return self._lock

    # ---- unit mapping (pure) -------------------------------------------------------------------
    def joint_index(self, servo_id: int) -> int:
        try:
            return self._index[int(servo_id)]
        except KeyError:
            raise KeyError(f"servo ID {servo_id}: not on this robot "
                           f"(IDs {sorted(self._index)})") from None

    def shaft_from_joint(self, joint_index: int, q_rad: float) -> float:
        return self.transmissions[joint_index].joint_rad_to_shaft_rad(q_rad)

    def joint_from_shaft(self, joint_index: int, shaft_rad: float) -> float:
        return self.transmissions[joint_index].shaft_rad_to_joint_rad(shaft_rad)

    # ---- ServoBackend --------------------------------------------------------------------------
    def ids(self) -> list:
        return list(self._index)

    def set_goal(self, servo_id: int, position_rad: float) -> None:
        j = self.joint_index(servo_id)
        with self._lock:
            self.plant.set_joint_target(j, self.joint_from_shaft(j, position_rad))

    def set_torque(self, servo_id: int, enabled: bool) -> None:
        j = self.joint_index(servo_id)
        with self._lock:
            self.plant.set_torque(j, enabled)

    def state(self, servo_id: int) -> ShaftState:
        j = self.joint_index(servo_id)
        with self._lock:
            q, qd, torque = self.plant.joint_state(j)
        d = self._direction[j]
        return ShaftState(position_rad=self.shaft_from_joint(j, q), velocity_rad_s=d * qd,
                          current_a=d * torque / self.torque_constant_nm_per_a)

    def advance(self, now_s: float) -> None:
        with self._lock:
            self.advance_locked(now_s)

    def advance_locked(self, now_s: float) -> None:
        """advance() for a caller that already holds `lock` (to read the plant at the same time)."""
        if self._clock_offset_s is None:
            self._clock_offset_s = now_s - self.plant.time_s
        target = now_s - self._clock_offset_s
        gap = target - self.plant.time_s
        if gap > self.max_catch_up_s:
            excess = gap - self.max_catch_up_s
            self.paused_s += excess
            self._clock_offset_s += excess
            target -= excess
        self.plant.step_to(target)
