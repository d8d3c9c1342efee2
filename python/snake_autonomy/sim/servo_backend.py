"""What the mocked servo bus asks of the physics behind its servos.

The mocked bus (snake_autonomy.sim.mock_servo_bus) owns the Protocol 2.0 side: packets, each servo's
control-table memory, fault injection. Whatever moves the servo shafts sits behind this interface:
a first-order servo model for driver tests (KinematicServoBackend, in mock_servo_bus's package), or
the MuJoCo plant (snake_autonomy.sim.plant) for the simulated robot.

Units are those of the servo shaft, not of the robot's joints: radians from the servo's centre
(the control table's position_centre_ticks, 2048 on the XH540), positive in the servo's own direction.
The mapping between joint angles and shaft angles (servo direction and zero offset from the robot
YAML) belongs to whoever knows the robot:
the driver on one side, the plant's adapter on the other.
"""
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass


@dataclass
class ShaftState:
    position_rad: float   # from the servo centre (the table's position_centre_ticks)
    velocity_rad_s: float
    current_a: float      # signed, as Present Current reports it
    temperature_c: float = 35.0
    voltage_v: float = 12.0


class ServoBackend(ABC):
    """Physics of the servos on one bus, addressed by Dynamixel ID."""

    @abstractmethod
    def ids(self) -> list:
        """IDs of the servos this backend moves."""

    @abstractmethod
    def set_goal(self, servo_id: int, position_rad: float) -> None:
        """A new Goal Position (already within the servo's limits)."""

    @abstractmethod
    def set_torque(self, servo_id: int, enabled: bool) -> None:
        """Torque Enable: a servo without torque goes limp (holds no position)."""

    @abstractmethod
    def state(self, servo_id: int) -> ShaftState:
        """Present position, velocity, current (and temperature, voltage) of one servo."""

    @abstractmethod
    def advance(self, now_s: float) -> None:
        """Bring the physics up to time now_s (monotonic seconds); called before reads and writes."""


class ShaftUnits:
    """A backend's shaft state <-> a servo's raw control-table values, by the control table's scales
    (position resolution and centre, velocity, current and voltage units): what both simulated buses
    (the pty mock's ShaftHooks and the batch simulator's in-process bus) write as Present values and
    read as goals. A servo model with another resolution converts through its own YAML."""

    def __init__(self, table):
        self.rad_per_tick = table.at("present_position").scale * math.pi / 180.0
        self.rad_s_per_unit = table.at("present_velocity").scale * 2.0 * math.pi / 60.0
        self.amps_per_unit = table.at("present_current").scale * 1e-3
        self.volts_per_unit = table.at("present_input_voltage").scale
        self.centre = table.position_centre_ticks

    def present(self, st: ShaftState):
        """(position ticks, velocity units, current units, voltage units, temperature C) of `st`."""
        return (round(st.position_rad / self.rad_per_tick) + self.centre,
                round(st.velocity_rad_s / self.rad_s_per_unit),
                round(st.current_a / self.amps_per_unit), round(st.voltage_v / self.volts_per_unit),
                round(st.temperature_c))

    def goal_rad(self, ticks: int) -> float:
        """A Goal Position (ticks) as a shaft angle from the centre."""
        return (ticks - self.centre) * self.rad_per_tick
