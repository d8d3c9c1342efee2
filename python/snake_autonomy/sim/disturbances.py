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


@dataclass(frozen=True)
class DisturbanceTrigger:
    """A push or twist of a mission file, fired at a time or when the robot is mid-leg.

    ``time_s``: seconds after the mission start; or ``waypoint`` + ``distance_m``: when that
    waypoint is the target and the robot's true centre of mass is within distance_m of it (so the
    push lands mid-leg whatever the robot's speed)."""
    link: str
    force_n: Optional[Sequence[float]] = None
    torque_nm: Optional[Sequence[float]] = None
    duration_s: float = 0.1
    time_s: Optional[float] = None
    waypoint: Optional[int] = None
    distance_m: Optional[float] = None

    def due(self, t_mission_s: float, target_index: int, distance_m: float) -> bool:
        if self.time_s is not None:
            return t_mission_s >= self.time_s
        return target_index == self.waypoint and distance_m <= self.distance_m

    def at(self, time_s: float) -> Disturbance:
        return Disturbance(time_s=time_s, link=self.link, force_n=self.force_n,
                           torque_nm=self.torque_nm, duration_s=self.duration_s)

    def describe(self) -> str:
        what = (f"push {list(self.force_n)} N" if self.force_n is not None
                else f"twist {list(self.torque_nm)} N m")
        when = (f"at {self.time_s:g} s" if self.time_s is not None
                else f"{self.distance_m:g} m before waypoint {self.waypoint}")
        return f"{what} on {self.link} for {self.duration_s:g} s, {when}"


TRIGGER_KEYS = ("link", "force_n", "torque_nm", "duration_s", "time_s", "waypoint", "distance_m")


def parse_triggers(raw, num_waypoints: int, where: str = "disturbances") -> List[DisturbanceTrigger]:
    """A mission's ``disturbances:`` list; ValueError listing every problem."""
    if raw is None:
        return []
    problems, out = [], []
    if not isinstance(raw, list):
        raise ValueError(f"{where}: expected a list, got {raw!r}")

    def vec(i, key, value):
        if value is None:
            return None
        if (not isinstance(value, (list, tuple)) or len(value) != 3
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)):
            problems.append(f"{where}[{i}].{key}: expected 3 numbers, got {value!r}")
            return None
        return tuple(float(x) for x in value)

    for i, item in enumerate(raw):
        if not isinstance(item, dict):
            problems.append(f"{where}[{i}]: expected a mapping, got {item!r}")
            continue
        unknown = sorted(set(item) - set(TRIGGER_KEYS))
        if unknown:
            problems.append(f"{where}[{i}]: unknown key(s) {unknown}; known: {', '.join(TRIGGER_KEYS)}")
        link = item.get("link")
        if not isinstance(link, str) or not link:
            problems.append(f"{where}[{i}].link: expected a body name (base_link, link_1 ...), got {link!r}")
        force, torque = vec(i, "force_n", item.get("force_n")), vec(i, "torque_nm", item.get("torque_nm"))
        if (item.get("force_n") is None) == (item.get("torque_nm") is None):
            problems.append(f"{where}[{i}]: give exactly one of force_n, torque_nm")
        duration = item.get("duration_s", 0.1)
        if not isinstance(duration, (int, float)) or isinstance(duration, bool) or not duration > 0:
            problems.append(f"{where}[{i}].duration_s: must be > 0, got {duration!r}")
        time_s, wp, dist = item.get("time_s"), item.get("waypoint"), item.get("distance_m")
        if time_s is not None:
            if wp is not None or dist is not None:
                problems.append(f"{where}[{i}]: give time_s or waypoint + distance_m, not both")
            elif not isinstance(time_s, (int, float)) or isinstance(time_s, bool) or time_s < 0:
                problems.append(f"{where}[{i}].time_s: must be >= 0, got {time_s!r}")
        else:
            if not (isinstance(wp, int) and not isinstance(wp, bool) and 0 <= wp < num_waypoints):
                problems.append(f"{where}[{i}].waypoint: expected a waypoint index 0..{num_waypoints - 1}, "
                                f"got {wp!r}")
            if not isinstance(dist, (int, float)) or isinstance(dist, bool) or not dist > 0:
                problems.append(f"{where}[{i}].distance_m: must be > 0, got {dist!r}")
        if not problems:
            out.append(DisturbanceTrigger(link=link, force_n=force, torque_nm=torque, duration_s=float(duration),
                                          time_s=None if time_s is None else float(time_s),
                                          waypoint=wp, distance_m=None if dist is None else float(dist)))
    if problems:
        raise ValueError("; ".join(problems))
    return out
