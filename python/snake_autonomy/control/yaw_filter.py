"""The 10-sample moving average of the centre-of-mass yaw (thesis section 3.2.2).

Samples are unwrapped against the previous one before averaging, so a heading that crosses +-pi
averages to a heading near +-pi, never to 0. The output is wrapped back to [-pi, pi].
"""
import math
from collections import deque
from typing import Optional

from .angles import wrap


class YawMovingAverage:
    """Moving average of yaw over the last ``window`` samples, continuous across +-pi.

    Feed it every pose (30-100 Hz); read ``value`` at the controller's 1 Hz.
    """

    def __init__(self, window: int = 10):
        if not isinstance(window, int) or isinstance(window, bool) or window < 1:
            raise ValueError(f"window: must be a positive integer, got {window!r}")
        self.window = window
        self._samples = deque(maxlen=window)   # unwrapped, rad
        self._last: Optional[float] = None     # last unwrapped sample, rad

    def reset(self) -> None:
        """Forget every sample (after a stale or lost pose: old samples are not evidence)."""
        self._samples.clear()
        self._last = None

    def add(self, yaw_rad: float) -> float:
        """Adds one yaw sample (any branch, rad) and returns the filtered yaw in [-pi, pi]."""
        if not math.isfinite(yaw_rad):
            raise ValueError(f"yaw_rad: must be finite, got {yaw_rad!r}")
        if self._last is None:
            unwrapped = wrap(yaw_rad)
        else:
            unwrapped = self._last + wrap(yaw_rad - self._last)
        self._last = unwrapped
        self._samples.append(unwrapped)
        return self.value

    @property
    def count(self) -> int:
        return len(self._samples)

    @property
    def full(self) -> bool:
        return len(self._samples) == self.window

    @property
    def value(self) -> Optional[float]:
        """The filtered yaw in [-pi, pi], or None before the first sample."""
        if not self._samples:
            return None
        return wrap(sum(self._samples) / len(self._samples))
