"""Angle helpers shared by the tracker, the yaw filter and the pose remapper (radians throughout)."""
import math


def wrap(angle_rad: float) -> float:
    """Thesis eq. 3.32: wrap(a) = atan2(sin a, cos a), in [-pi, pi]."""
    return math.atan2(math.sin(angle_rad), math.cos(angle_rad))


def clamp(value: float, low: float, high: float) -> float:
    return max(low, min(high, value))
