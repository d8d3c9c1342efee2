"""Closed-loop waypoint tracking: thesis Algorithm 1 (section 3.7, Table 3.1), ROS-free.

One call of :meth:`WaypointTracker.update` is one 1 Hz control step on an already-filtered
centre-of-mass pose (x, y in the world frame, yaw of the virtual chassis, REP 103: yaw
counter-clockwise positive). It returns a :class:`TrackerCommand`: the mode, the gait to run and the
steering correction delta, with every error the decision was based on.

Sign convention (REP 103). A positive yaw error means the goal lies counter-clockwise of the
current heading, so Algorithm 1 line 22 (psi_e > +psi_turn -> phi_L) makes ``turn_left`` the gait
that turns the robot counter-clockwise (positive yaw rate), ``turn_right`` clockwise; the same for
``near_turn_left`` / ``near_turn_right`` (the NEAR turn, lines 37-42, amplitudes a_um).

Gaits. ``mode`` is the locomotion mode; ``gait`` is the gait the robot should run after this step.
Algorithm 1 calls UPDATECPG only when it enters a turn or steers while sidewinding; on the return
from a turn to mode 1 (lines 29-30, 44-45) it calls nothing, while Table 3.1 says "switch back to
sidewind". We command ``sidewind`` at that step, with the previous delta (Algorithm 1 does not
compute a new one in that step). When a waypoint is reached (line 36) the running gait continues;
after the last waypoint the gait is ``stop`` (line 15, STOPCPG), which the mission node maps to the
driver's ``hold`` gait.

Two literal properties of Algorithm 1 are kept by default and can be changed (``turn_exit_any_branch``):
a FAR turn (mode 2) is left only in the FAR branch and a NEAR turn (mode 3) only in the NEAR branch.
Printed as is, a robot that crosses d_th while turning keeps turning until it crosses back.
With ``turn_exit_any_branch=True`` either turn mode returns to mode 1 as soon as |psi_e| <= psi_wp,
in either branch.

Approach against the waypoint's heading (``far_blend_max_gap``, default pi: off, Algorithm 1 as
printed). The combined error of line 8 is a weighted sum of two wrapped angles. When the waypoint's
heading points away from the robot (heading_k and the bearing to the waypoint about 180 deg apart),
its zero is the bisector of the two through heading_k, which on either side of the waypoint's axis
points back towards that axis: a robot approaching from behind the waypoint zig-zags along the axis
at the distance where w is about 0.5 and never reaches d_th (measured on the simulated COBRA: every
start behind the waypoint, whatever the gait speed). With a gap limit, a FAR-branch step whose
|wrap(heading_k - bearing)| exceeds it steers on the relative error alone (w = 0): go to the
waypoint, align in place there (the NEAR branch, unchanged).
"""
import math
from dataclasses import dataclass
from typing import List, Sequence, Tuple

from .angles import clamp, wrap
from .weight import blend_weight, combined_yaw_error

# Gait names the tracker commands. The mission maps them to the gait library (config/gaits.yaml).
SIDEWIND = "sidewind"
TURN_LEFT = "turn_left"
TURN_RIGHT = "turn_right"
NEAR_TURN_LEFT = "near_turn_left"
NEAR_TURN_RIGHT = "near_turn_right"
STOP = "stop"
TRACKER_GAITS = (SIDEWIND, TURN_LEFT, TURN_RIGHT, NEAR_TURN_LEFT, NEAR_TURN_RIGHT, STOP)

MODE_SIDEWIND = 1
MODE_FAR_TURN = 2
MODE_NEAR_TURN = 3


@dataclass(frozen=True)
class TrackerParams:
    """Algorithm 1's parameter table (radians, metres); the defaults are the table's values."""
    d_th: float = 0.35                   # m, NEAR below or at this distance
    psi_wp: float = math.radians(30.0)   # rad, waypoint yaw tolerance / end of a turn
    psi_turn: float = math.radians(40.0)  # rad, yaw error that starts a FAR turn
    delta0: float = math.radians(14.0)   # rad, base steering offset
    delta_lim: float = math.radians(7.0)  # rad, limit of the proportional steering term
    kp: float = 1.0                      # steering gain (rad/rad)
    delta_turn: float = math.radians(20.0)  # rad, the "delta > +-20 deg" of lines 22 and 25
    turn_exit_any_branch: bool = False   # see the module docstring
    far_blend_max_gap: float = math.pi   # rad; see the module docstring (pi: off)

    def problems(self) -> List[str]:
        """Every invalid parameter, each naming the key and its value (empty when valid)."""
        out = []
        for name in ("d_th", "psi_wp", "psi_turn", "delta0", "delta_lim", "kp", "delta_turn", "far_blend_max_gap"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                out.append(f"{name}: must be a finite number, got {value!r}")
        if out:
            return out
        for name in ("d_th", "psi_wp", "psi_turn", "kp", "delta_turn", "far_blend_max_gap"):
            if getattr(self, name) <= 0:
                out.append(f"{name}: must be positive, got {getattr(self, name)!r}")
        if self.delta_lim < 0:
            out.append(f"delta_lim: must not be negative, got {self.delta_lim!r}")
        for name in ("psi_wp", "psi_turn"):
            if getattr(self, name) >= math.pi:
                out.append(f"{name}: must be below pi rad (180 deg), got {getattr(self, name)!r}")
        if self.psi_wp > self.psi_turn:
            out.append(f"psi_wp: must not exceed psi_turn ({math.degrees(self.psi_turn):.6g} deg), "
                       f"got {math.degrees(self.psi_wp):.6g} deg")
        if self.far_blend_max_gap > math.pi:
            out.append(f"far_blend_max_gap: must not exceed pi rad (180 deg: off), got {self.far_blend_max_gap!r}")
        if not isinstance(self.turn_exit_any_branch, bool):
            out.append(f"turn_exit_any_branch: must be true or false, got {self.turn_exit_any_branch!r}")
        return out


@dataclass(frozen=True)
class TrackerCommand:
    """The outcome of one control step.

    The errors refer to waypoint ``target_index``: the active waypoint at the start of the step.
    ``waypoint_index`` is the active waypoint after the step (target_index + 1 when ``reached``).
    """
    mode: int                 # 1 sidewind, 2 FAR turn, 3 NEAR turn
    waypoint_index: int       # 0-based, == number of waypoints when done
    target_index: int         # the waypoint the errors below refer to
    reached: bool             # target_index was reached in this step
    done: bool
    delta_rad: float          # steering correction (the previous step's when not recomputed)
    gait: str                 # one of TRACKER_GAITS
    steer: bool               # apply delta (sidewinding); False for turns and stop
    w: float                  # blend weight of eq. 3.33
    yaw_error_abs: float      # rad, wrap(heading_k - yaw)
    yaw_error_rel: float      # rad, wrap(bearing to waypoint - yaw)
    yaw_error: float          # rad, w * abs + (1 - w) * rel
    distance: float           # m
    branch: str               # "far", "near" or "done"
    action: str               # what the step did, Table 3.1's wording


Waypoint = Tuple[float, float, float]


class WaypointTracker:
    """Algorithm 1 as a state machine stepped at 1 Hz.

    ``WaypointTracker(waypoints, **params)``: waypoints are (x_m, y_m, heading_rad) in the world
    frame; params are :class:`TrackerParams` fields (radians, metres).
    """

    def __init__(self, waypoints: Sequence[Sequence[float]], **params):
        unknown = sorted(set(params) - set(TrackerParams.__dataclass_fields__))
        problems = [f"{name}: unknown tracker parameter (value {params[name]!r})" for name in unknown]
        if not unknown:
            self.params = TrackerParams(**params)
            problems += self.params.problems()
        wps: List[Waypoint] = []
        if len(waypoints) == 0:
            problems.append("waypoints: at least one waypoint is needed, got none")
        for i, wp in enumerate(waypoints):
            try:
                x, y, h = (float(v) for v in wp)
            except (TypeError, ValueError):
                problems.append(f"waypoints[{i}]: expected (x_m, y_m, heading_rad), got {wp!r}")
                continue
            if not all(math.isfinite(v) for v in (x, y, h)):
                problems.append(f"waypoints[{i}]: every value must be finite, got {wp!r}")
                continue
            wps.append((x, y, h))
        if problems:
            raise ValueError("invalid waypoint tracker configuration:\n  " + "\n  ".join(problems))
        self.waypoints: Tuple[Waypoint, ...] = tuple(wps)
        self.reset()

    def reset(self) -> None:
        """Algorithm 1 line 1-2: k = first waypoint, mode 1, sidewinding with unmodified amplitudes."""
        self._k = 0
        self._mode = MODE_SIDEWIND
        self._gait = SIDEWIND
        # STARTCPG(a_sw): unmodified amplitudes, so the steering correction starts at 0.
        self._delta = 0.0
        self._last = None

    def skip(self) -> None:
        """Counts the active waypoint as reached without a control step (another controller drove the
        robot there: a mission's navigate_to leg). The next waypoint becomes active, sidewinding from
        mode 1 with an unmodified amplitude, as at the start."""
        if self._k < len(self.waypoints):
            self._k += 1
        self._mode, self._gait, self._delta = MODE_SIDEWIND, SIDEWIND, 0.0
        if self.done:
            self._gait = STOP

    @property
    def mode(self) -> int:
        return self._mode

    @property
    def waypoint_index(self) -> int:
        return self._k

    @property
    def done(self) -> bool:
        return self._k >= len(self.waypoints)

    @property
    def delta_rad(self) -> float:
        return self._delta

    @property
    def gait(self) -> str:
        return self._gait

    def errors(self, x: float, y: float, yaw_rad: float, index: int):
        """(distance, yaw_error_abs, yaw_error_rel, w, yaw_error) to waypoint ``index``: lines 5-8
        (w = 0 in the FAR branch when heading and bearing differ by more than far_blend_max_gap)."""
        px, py, heading = self.waypoints[index]
        dx, dy = px - x, py - y
        distance = math.hypot(dx, dy)
        bearing = math.atan2(dy, dx)
        rel = wrap(bearing - yaw_rad)
        abs_ = wrap(heading - yaw_rad)
        w = blend_weight(distance)
        if distance > self.params.d_th and abs(wrap(heading - bearing)) > self.params.far_blend_max_gap:
            w = 0.0
        return distance, abs_, rel, w, combined_yaw_error(abs_, rel, w)

    def update(self, x: float, y: float, yaw_rad: float) -> TrackerCommand:
        """One control step of Algorithm 1 (lines 4-13) on a filtered CoM pose."""
        for name, value in (("x", x), ("y", y), ("yaw_rad", yaw_rad)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{name}: must be a finite number, got {value!r}")
        p = self.params
        n = len(self.waypoints)
        if self._k >= n:
            distance, e_abs, e_rel, w, e = self.errors(x, y, yaw_rad, n - 1)
            self._gait = STOP
            return self._command(n - 1, False, distance, e_abs, e_rel, w, e, "done", "mission complete")

        k = self._k
        distance, e_abs, e_rel, w, e = self.errors(x, y, yaw_rad, k)
        reached = False
        if distance > p.d_th:
            branch = "far"
            action = self._far_branch(e)
        else:
            branch = "near"
            action, reached = self._near_branch(e)
        if self._k >= n:
            self._gait = STOP   # line 15: STOPCPG after the last waypoint
            action += "; mission complete"
        return self._command(k, reached, distance, e_abs, e_rel, w, e, branch, action)

    # -- Algorithm 1, lines 16-32 ------------------------------------------------------------------
    def _far_branch(self, e: float) -> str:
        p = self.params
        if self._mode == MODE_SIDEWIND:
            if abs(e) <= p.psi_turn:                                     # line 18
                self._delta = p.delta0 + clamp(p.kp * e, -p.delta_lim, p.delta_lim)  # line 19
                self._gait = SIDEWIND                                    # lines 20-21
                return "sidewind with steering correction"
            # lines 22 and 25 run only when |psi_e| > psi_turn, where line 19 did not run
            # in this step, so self._delta here is the delta of the PREVIOUS control step. That is
            # implemented literally: a previous delta > +20 deg turns left even when psi_e < -psi_turn.
            if e > p.psi_turn or self._delta > p.delta_turn:             # line 22
                self._mode = MODE_FAR_TURN                               # line 23
                self._gait = TURN_LEFT                                   # line 24, phi_L
                return "switch to turn-in-place (left)"
            if e < -p.psi_turn or self._delta < -p.delta_turn:           # line 25
                self._mode = MODE_FAR_TURN                               # line 26
                self._gait = TURN_RIGHT                                  # line 27, phi_R
                return "switch to turn-in-place (right)"
            return "no change"   # unreachable: |e| > psi_turn means one of the two holds
        if (self._mode == MODE_FAR_TURN or (self._mode == MODE_NEAR_TURN and p.turn_exit_any_branch)) \
                and abs(e) <= p.psi_wp:                                   # line 29
            self._mode = MODE_SIDEWIND                                   # line 30
            self._gait = SIDEWIND   # Table 3.1 "switch back to sidewind", with the previous delta
            return "switch back to sidewind"
        return "keep turning"

    # -- Algorithm 1, lines 33-47 ------------------------------------------------------------------
    def _near_branch(self, e: float):
        p = self.params
        if self._mode == MODE_SIDEWIND:
            if abs(e) <= p.psi_wp:                                       # line 35
                self._k += 1                                             # line 36
                return "waypoint reached", True
            if e > p.psi_wp:                                             # line 37
                self._mode = MODE_NEAR_TURN                              # line 38
                self._gait = NEAR_TURN_LEFT                              # line 39, a_um, phi_L
                return "turn to align heading (left)", False
            self._mode = MODE_NEAR_TURN                                  # lines 40-41
            self._gait = NEAR_TURN_RIGHT                                 # line 42, a_um, phi_R
            return "turn to align heading (right)", False
        if (self._mode == MODE_NEAR_TURN or (self._mode == MODE_FAR_TURN and p.turn_exit_any_branch)) \
                and abs(e) <= p.psi_wp:                                   # line 44
            self._mode = MODE_SIDEWIND                                   # line 45
            self._gait = SIDEWIND
            return "switch to sidewind (then detect reached)", False
        return "keep turning", False

    def _command(self, target, reached, distance, e_abs, e_rel, w, e, branch, action) -> TrackerCommand:
        cmd = TrackerCommand(
            mode=self._mode, waypoint_index=self._k, target_index=target, reached=reached,
            done=self.done, delta_rad=self._delta, gait=self._gait, steer=self._gait == SIDEWIND,
            w=w, yaw_error_abs=e_abs, yaw_error_rel=e_rel, yaw_error=e, distance=distance,
            branch=branch, action=action)
        self._last = cmd
        return cmd
