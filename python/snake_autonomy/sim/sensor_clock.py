"""When a fixed-rate sensor is due: on the grid k / rate_hz of simulation time, never drifting."""
import math


class SensorClock:
    def __init__(self, rate_hz: float):
        self.period_s = 1.0 / rate_hz
        self._next_k = 0

    def due(self, t_s: float) -> bool:
        return t_s >= self._next_k * self.period_s - 1e-9

    @property
    def next_s(self) -> float:
        """The next grid point due."""
        return self._next_k * self.period_s

    def tick(self, t_s: float) -> None:
        """Mark a sample taken at t_s: the next is due at the first grid point after it."""
        self._next_k = int(math.floor(t_s / self.period_s + 1e-9)) + 1
