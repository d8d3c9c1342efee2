"""Pushes and twists on command: constant world-frame wrenches on chosen links for short windows.

A disturbance is (time_s, link, force_n or torque_nm, duration_s). The plant splits its steps at
every window's start and end, so a window is applied for exactly round(duration / dt) steps, and
writes the sum of active wrenches into MuJoCo's xfrc_applied (force at the body's centre of mass,
world frame). The impulse of a push is force x duration (e.g. 60 N for 0.1 s = 6 N s, enough to
move the 6 kg COBRA by about 1 m/s before friction stops it).
"""
from dataclasses import dataclass
from typing import Iterable, List, Optional, Sequence

import numpy as np


@dataclass(frozen=True)
class Disturbance:
    time_s: float
    link: str                                   # body name: base_link or link_1 ... link_N
    force_n: Optional[Sequence[float]] = None   # world frame, applied at the link's CoM
    torque_nm: Optional[Sequence[float]] = None  # world frame
    duration_s: float = 0.1

    @property
    def end_s(self) -> float:
        return self.time_s + self.duration_s

    def wrench(self) -> np.ndarray:
        """[fx fy fz tx ty tz] as MuJoCo's xfrc_applied row."""
        out = np.zeros(6)
        if self.force_n is not None:
            out[:3] = self.force_n
        if self.torque_nm is not None:
            out[3:] = self.torque_nm
        return out


class DisturbanceSchedule:
    """The disturbances of one run, sorted by start; answers what is active at a time."""

    def __init__(self, disturbances: Iterable = ()):
        items = [d if isinstance(d, Disturbance) else Disturbance(
            time_s=d.time_s, link=d.link, force_n=d.force_n, torque_nm=d.torque_nm,
            duration_s=d.duration_s) for d in disturbances]
        self.items: List[Disturbance] = sorted(items, key=lambda d: d.time_s)

    def add(self, disturbance: Disturbance) -> None:
        self.items.append(disturbance)
        self.items.sort(key=lambda d: d.time_s)

    def links(self) -> set:
        return {d.link for d in self.items}

    def active(self, t_s: float) -> List[Disturbance]:
        """Disturbances whose window [start, end) contains t_s."""
        return [d for d in self.items if d.time_s <= t_s < d.end_s]

    def next_event_after(self, t_s: float) -> float:
        """The first window start or end strictly after t_s (inf when none is left)."""
        events = [x for d in self.items for x in (d.time_s, d.end_s) if x > t_s]
        return min(events, default=float("inf"))
