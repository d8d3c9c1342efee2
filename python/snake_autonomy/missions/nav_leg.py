"""The mission leg `navigate_to`, ROS-free: a waypoint the obstacle-aware planner drives to.

In a mission file a waypoint may be a mapping with a navigation leg instead of a tracker pose::

    waypoints:
      - [0.5, 0.0, 0]                                         # the waypoint tracker drives
      - {navigate_to: {x_m: 2.0, y_m: 0.5, radius_m: 0.2}}    # the planner (move_base) drives
      - [2.5, 0.5, 0]                                         # the tracker again

navigate_to keys: ``x_m``, ``y_m`` (the goal in the mission's world frame, required), ``heading_deg``
(the goal pose's heading, default 0: the rectilinear planner drives into a disc and ignores it; the
run's metrics report it as the waypoint's heading), ``radius_m`` (the leg also counts as reached once the
centre of mass is this close to the goal, and the goal is cancelled; absent: only the planner's own
goal check ends it) and ``time_limit_s`` (the leg aborts the mission after this long; the mission's
``time_limit_s`` applies as well). Checked by `parse_nav_leg` with the rest of the mission.

MissionRunner hands a leg to a `Navigator` (the ROS side's nodes.mission_nav_leg.MoveBaseNavigator:
a move_base action goal) and polls it every control tick: the leg is reached when the navigator
reports SUCCEEDED (or inside radius_m); a FAILED navigator (goal aborted, preempted, rejected, no
server) or the leg's time limit aborts the mission with the reason, naming the leg. While a leg runs
the mission node sends no gait command: the planner owns locomotion.
"""
from dataclasses import dataclass
from typing import List, Optional, Protocol, Tuple

from .fields import is_number, keyed_mapping

NAV_LEG_KEYS = ("x_m", "y_m", "heading_deg", "radius_m", "time_limit_s")
MAX_COORDINATE_M = 1000.0
MAX_RADIUS_M = 100.0
MAX_LEG_TIME_S = 86400.0
#: What the tracking status reports as the gait while a leg runs (the planner commands the gaits).
NAVIGATE_TO = "navigate_to"
#: Navigator states.
PENDING, ACTIVE, SUCCEEDED, FAILED = "pending", "active", "succeeded", "failed"


@dataclass(frozen=True)
class NavLegSpec:
    x_m: float
    y_m: float
    heading_deg: float = 0.0
    radius_m: Optional[float] = None
    time_limit_s: Optional[float] = None

    def describe(self, index: int) -> str:
        """The leg as messages name it: waypoints[i] navigate_to (x, y)."""
        return f"waypoints[{index}] navigate_to ({self.x_m:g}, {self.y_m:g})"


class Navigator(Protocol):
    def send(self, index: int, leg: NavLegSpec) -> None:
        """Start driving to the leg's goal (returns at once; poll() tells how it goes)."""

    def poll(self) -> Tuple[str, str]:
        """(state, text): state PENDING, ACTIVE, SUCCEEDED or FAILED, text what happened (why it failed)."""

    def cancel(self) -> None:
        """Stop the leg's goal (the mission ended or holds); nothing when none is under way."""


def parse_nav_leg(raw, where: str, problems: List[str]) -> Optional[NavLegSpec]:
    """A NavLegSpec from a waypoint's `navigate_to:` mapping; every problem appended, naming key and value."""
    before = len(problems)
    if not keyed_mapping(raw, where, NAV_LEG_KEYS, problems):
        return None
    for key in ("x_m", "y_m"):
        v = raw.get(key)
        if key not in raw:
            problems.append(f"{where}.{key}: missing (the goal in the world frame, m)")
        elif not (is_number(v) and abs(v) <= MAX_COORDINATE_M):
            problems.append(f"{where}.{key}: must be a number within +-{MAX_COORDINATE_M:g} m, got {v!r}")
    heading = raw.get("heading_deg", 0.0)
    if not (is_number(heading) and abs(heading) <= 360.0):
        problems.append(f"{where}.heading_deg: must be a number within +-360, got {heading!r}")
    for key, bound, unit in (("radius_m", MAX_RADIUS_M, "m"), ("time_limit_s", MAX_LEG_TIME_S, "s")):
        v = raw.get(key)
        if v is not None and not (is_number(v) and 0 < v <= bound):
            problems.append(f"{where}.{key}: must be a number in (0, {bound:g}] {unit}, got {v!r}")
    if len(problems) > before:
        return None
    radius, limit = raw.get("radius_m"), raw.get("time_limit_s")
    return NavLegSpec(float(raw["x_m"]), float(raw["y_m"]), float(heading),
                      float(radius) if radius is not None else None, float(limit) if limit is not None else None)
