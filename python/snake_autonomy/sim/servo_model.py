"""A first-order servo model behind the mocked bus: goal tracking with a velocity limit.

Each shaft follows its goal as a first-order lag (time constant ``time_constant_s``) whose speed
is capped at ``max_velocity_rad_s``, so present position lags goal as on hardware: a large step
moves at constant speed, then settles exponentially. Torque off: the shaft goes limp (holds no
position, no gravity here, so it stays where it is with zero velocity and current). Integrated
exactly between calls of ``advance``: the result does not depend on how often the bus is read.
"""
import math
from dataclasses import dataclass

from snake_autonomy.sim.servo_backend import ServoBackend, ShaftState


@dataclass
class KinematicServoParams:
    max_velocity_rad_s: float = 4.8      # XH540-W270: 46 rpm no-load at 12 V
    time_constant_s: float = 0.05        # the position loop's lag
    amps_per_rad: float = 2.0            # current drawn per radian of tracking error
    max_current_a: float = 4.4           # XH540-W270 stall current at 12 V
    temperature_c: float = 35.0
    voltage_v: float = 12.0

    def validate(self):
        for name in ("max_velocity_rad_s", "time_constant_s", "max_current_a"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"KinematicServoParams.{name}: {value!r} is not a positive number")


def track(position_rad: float, goal_rad: float, dt_s: float, vmax: float, tau: float):
    """Exact step of x' = clamp((goal - x) / tau, -vmax, vmax): (position, velocity) after dt_s."""
    error = goal_rad - position_rad
    if dt_s <= 0:
        speed = error / tau
        return position_rad, max(-vmax, min(vmax, speed))
    band = vmax * tau  # inside it the lag is linear, outside the speed saturates
    if abs(error) > band:
        direction = 1.0 if error > 0 else -1.0
        t_saturated = (abs(error) - band) / vmax
        if dt_s <= t_saturated:
            return position_rad + direction * vmax * dt_s, direction * vmax
        position_rad += direction * vmax * t_saturated
        dt_s -= t_saturated
        error = goal_rad - position_rad
    error *= math.exp(-dt_s / tau)
    return goal_rad - error, error / tau


class KinematicServoBackend(ServoBackend):
    """Servos without a body: each shaft tracks its goal (see module docstring)."""

    def __init__(self, ids, params: KinematicServoParams = None, initial_rad: float = 0.0):
        self._params = params or KinematicServoParams()
        self._params.validate()
        self._ids = [int(i) for i in ids]
        if len(set(self._ids)) != len(self._ids):
            raise ValueError(f"ids: {self._ids} has repeated IDs")
        self._pos = {i: float(initial_rad) for i in self._ids}
        self._vel = {i: 0.0 for i in self._ids}
        self._goal = {i: float(initial_rad) for i in self._ids}
        self._torque = {i: False for i in self._ids}
        self._t = None

    def ids(self) -> list:
        return list(self._ids)

    def set_goal(self, servo_id: int, position_rad: float) -> None:
        self._goal[servo_id] = float(position_rad)

    def set_torque(self, servo_id: int, enabled: bool) -> None:
        self._torque[servo_id] = bool(enabled)
        if not enabled:
            self._vel[servo_id] = 0.0

    def state(self, servo_id: int) -> ShaftState:
        p = self._params
        current = 0.0
        if self._torque[servo_id]:
            error = self._goal[servo_id] - self._pos[servo_id]
            current = max(-p.max_current_a, min(p.max_current_a, p.amps_per_rad * error))
        return ShaftState(position_rad=self._pos[servo_id], velocity_rad_s=self._vel[servo_id],
                          current_a=current, temperature_c=p.temperature_c, voltage_v=p.voltage_v)

    def advance(self, now_s: float) -> None:
        if self._t is None:
            self._t = now_s
            return
        dt = now_s - self._t
        if dt <= 0:
            return
        self._t = now_s
        p = self._params
        for i in self._ids:
            if self._torque[i]:
                self._pos[i], self._vel[i] = track(self._pos[i], self._goal[i], dt,
                                                   p.max_velocity_rad_s, p.time_constant_s)
            else:
                self._vel[i] = 0.0  # limp: no position held, nothing moves it here
