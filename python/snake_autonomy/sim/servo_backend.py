"""What the mocked servo bus asks of the physics behind its servos.

The mocked bus (snake_autonomy.sim.mock_servo_bus) owns the Protocol 2.0 side: packets, each servo's
control-table memory, fault injection. Whatever moves the servo shafts sits behind this interface:
a first-order servo model for driver tests (KinematicServoBackend, in mock_servo_bus's package), or
the MuJoCo plant (snake_autonomy.sim.plant) for the simulated robot.

Units are those of the servo shaft, not of the robot's joints: radians from the servo's centre
(tick 2048), positive in the servo's own direction. The mapping between joint angles and shaft
angles (servo direction and zero offset from the robot YAML) belongs to whoever knows the robot:
the driver on one side, the plant's adapter on the other.
"""
from abc import ABC, abstractmethod
from dataclasses import dataclass


@dataclass
class ShaftState:
    position_rad: float   # from the servo centre (tick 2048)
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
