"""A mission in progress, ROS-free: poses in (30-100 Hz), one decision per control tick (1 Hz) out.

The mission node wires it to topics; the simulator can drive it directly. Safety rules:

- locomotion runs only while the mission is running and the pose is fresh: a pose older than
  ``pose_timeout_s``, a pose source reporting lost tracking, or a non-finite pose all hold the
  robot (the tracker is not stepped: driving on a made-up pose is unsafe) and say so; tracking
  resumes when fresh poses have refilled the yaw filter;
- the mission ends (hold) when the last waypoint is reached, on abort and on its time limit;
- a waypoint with a scout stop (missions/scout.py): once reached, locomotion holds while the stop
  plans (a worker thread), raises, holds and lowers; `Decision.trajectory_active` then tells the
  caller not to send gait commands (the trajectory owns the joints). A failed plan is recorded in
  `scout_log` and the mission resumes; a stop failed once a trajectory was handed over (refused,
  aborted, no final status in time: the head may be up) aborts the mission, sending no gait. The
  time limit is checked only between scout stops (a raised head is lowered first); a stop needs
  `scout_planner` and `executor`, without them it is recorded as failed and skipped;
- a navigate_to leg (missions/nav_leg.py) is driven by a `Navigator` (the planner's move_base on the
  ROS side): the tracker is not stepped and `Decision.navigating` tells the caller not to send gait
  commands; the leg ends reached (the tracker goes on with the next waypoint) or aborts the mission
  with the navigator's reason, naming the leg. Abort, pause, time limit and close cancel the leg's goal
  (a leg paused is sent again on resume). Without a navigator a leg aborts the mission. A leg reached
  (the navigator's goal succeeded, or the centre of mass inside its ``radius_m``) is followed by its
  after-hold: the hold gait every tick for ``leg_hold_s`` (the body straightens and comes to rest), then
  the leg's scout stop or the tracker's gait at the next tick, so the driver hears a command every tick
  from the planner's last one on. A scout stop on the last waypoint (a leg's or the tracker's) ends the
  mission once the head is down.

Heading. The tracker's yaw is the direction the robot travels when it sidewinds. ``com_pose`` carries
the virtual chassis (x axis along the body, eq. 3.11-3.14); ``heading_offset_rad`` (config/tracker.yaml
``heading_offset_deg``) is added to its yaw: 0 where the virtual chassis yaw is the heading, as the
thesis states for COBRA; +90 deg on the simulated COBRA, which sidewinds towards the chassis's +y
(config/sim.yaml, measured there).
"""
import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

from ..control import TrackerCommand, WaypointTracker, YawMovingAverage
from .mission import Mission
from .nav_leg import FAILED as LEG_FAILED, NAVIGATE_TO, SUCCEEDED as LEG_SUCCEEDED, Navigator
from .scout import ScoutPlanner, ScoutRecord, ScoutStop, TrajectoryExecutor

IDLE, RUNNING, DONE, ABORTED, TIMEOUT = "idle", "running", "done", "aborted", "timeout"
NAN = float("nan")


@dataclass
class Decision:
    """What to send to the driver and what to report, for one control tick."""
    t_s: float
    gait: str                      # gait library name to command
    steer: bool
    delta_rad: float
    status: Dict[str, Any]         # TrackingStatus fields (minus header)
    hold: bool                     # locomotion held (stale pose or mission over)
    finished: bool = False         # the mission ended at this tick
    outcome: str = ""
    trajectory_active: bool = False  # a scout trajectory owns the joints: send no gait command
    navigating: bool = False       # a navigate_to leg runs: the planner drives, send no gait command
    leg_state: str = ""            # navigate_to: the leg's state or how it ended; "" on tracker waypoints
    command: Optional[TrackerCommand] = field(default=None, repr=False)


class MissionRunner:
    def __init__(self, mission: Mission, pose_timeout_s: float = 0.5, yaw_window: int = 10,
                 min_fresh_samples: Optional[int] = None, heading_offset_rad: float = 0.0,
                 scout_planner: Optional[ScoutPlanner] = None,
                 executor: Optional[TrajectoryExecutor] = None, navigator: Optional[Navigator] = None,
                 leg_hold_s: Optional[float] = None):
        """leg_hold_s: the after-hold of a reached navigate_to leg; None: the navigator's ``settle_s``
        (MoveBaseNavigator's ~nav_settle_s), 0 when it has none."""
        if not (isinstance(pose_timeout_s, (int, float)) and math.isfinite(pose_timeout_s) and pose_timeout_s > 0):
            raise ValueError(f"pose_timeout_s: must be a positive number, got {pose_timeout_s!r}")
        self.mission = mission
        self.tracker = WaypointTracker(mission.waypoints, **mission.tracker_kwargs())
        self.filter = YawMovingAverage(yaw_window)
        self.pose_timeout_s = float(pose_timeout_s)
        self.min_fresh_samples = yaw_window if min_fresh_samples is None else int(min_fresh_samples)
        if not (isinstance(heading_offset_rad, (int, float)) and math.isfinite(heading_offset_rad)):
            raise ValueError(f"heading_offset_rad: must be a finite number, got {heading_offset_rad!r}")
        self.heading_offset_rad = float(heading_offset_rad)
        self.state = IDLE
        self.outcome = ""
        self.t_start: Optional[float] = None
        self._xy = None
        self._pose_t: Optional[float] = None
        self._source_ok = True
        self._source_detail = ""
        self._stale_reason = "no pose yet"
        self._was_stale = True
        self.scout_planner, self.executor = scout_planner, executor
        self.scout: Optional[ScoutStop] = None
        self.scout_log: List[ScoutRecord] = []
        self._pool: Optional[ThreadPoolExecutor] = None
        self.paused: Optional[str] = None      # why the mission holds until resume() (a driver fault)
        self.navigator = navigator
        self._leg_t0: Optional[float] = None   # when the navigate_to leg under way was sent
        if leg_hold_s is None:
            leg_hold_s = getattr(navigator, "settle_s", 0.0)
        if not (isinstance(leg_hold_s, (int, float)) and math.isfinite(leg_hold_s) and leg_hold_s >= 0):
            raise ValueError(f"leg_hold_s: must be a number of seconds >= 0, got {leg_hold_s!r}")
        self.leg_hold_s = float(leg_hold_s)
        # a reached leg's after-hold under way: (until when, the leg's index, its leg_state)
        self._after_leg: Optional[Tuple[float, int, str]] = None

    @property
    def hold_gait(self) -> str:
        return self.mission.gaits["stop"]

    @property
    def running(self) -> bool:
        return self.state == RUNNING

    def start(self, t_s: float) -> None:
        if self.state != IDLE:
            raise RuntimeError(f"mission {self.mission.name!r} is {self.state}; load it again to rerun")
        self.state = RUNNING
        self.t_start = t_s

    def abort(self, reason: str = "aborted") -> None:
        if self.state == RUNNING:
            self.state = ABORTED
            self.outcome = f"aborted: {reason}"
            self._cancel_leg()

    def pause(self, reason: str) -> bool:
        """Hold until resume(), whatever the inputs do (a driver fault: the driver's recovery must not
        set the robot moving by itself). The waypoint is kept; the time limit runs on. False when not
        running or already paused."""
        if self.state != RUNNING or self.paused is not None:
            return False
        self.paused = reason
        self._cancel_leg()
        return True

    def resume(self) -> bool:
        """Go on after pause(): tracking restarts on fresh poses. False when not paused."""
        if self.paused is None or self.state != RUNNING:
            return False
        self.paused = None
        self._invalidate()
        self._stale_reason = "waiting for a pose after the pause"
        return True

    # -- inputs ------------------------------------------------------------------------------------
    def on_pose(self, t_s: float, x: float, y: float, yaw_rad: float) -> bool:
        """A centre-of-mass pose (any rate): position and virtual-chassis yaw (the heading offset is
        added here). Non-finite poses are dropped and count as lost."""
        if not all(math.isfinite(v) for v in (x, y, yaw_rad)):
            self._stale_reason = f"non-finite CoM pose ({x}, {y}, {yaw_rad})"
            self._invalidate()
            return False
        if self._pose_t is not None and t_s - self._pose_t > self.pose_timeout_s:
            self.filter.reset()   # after a gap the old yaw samples are not evidence any more
        self._xy = (x, y)
        self._pose_t = t_s
        self.filter.add(yaw_rad + self.heading_offset_rad)
        return True

    def set_source_status(self, ok: bool, detail: str = "") -> None:
        """The pose source's own verdict (the pose remapper's lost-tracking detection)."""
        if self._source_ok and not ok:
            self._invalidate()
        self._source_ok = bool(ok)
        self._source_detail = detail

    def _invalidate(self) -> None:
        self.filter.reset()
        self._pose_t = None

    def pose_problem(self, t_s: float) -> str:
        """Why the pose cannot be used at t_s, or '' when it is fresh."""
        if not self._source_ok:
            return f"pose source: {self._source_detail or 'tracking lost'}"
        if self._pose_t is None:
            return self._stale_reason
        age = t_s - self._pose_t
        if age > self.pose_timeout_s:
            return f"CoM pose is {age:.2f} s old (timeout {self.pose_timeout_s:g} s)"
        if self.filter.count < self.min_fresh_samples:
            return f"waiting for fresh poses ({self.filter.count}/{self.min_fresh_samples} yaw samples)"
        return ""

    # -- the control tick ----------------------------------------------------------------------------
    def step(self, t_s: float) -> Optional[Decision]:
        """One control tick; None when the mission is not running."""
        if self.state != RUNNING:
            return None
        n = len(self.mission.waypoints)
        if self.scout is not None:
            phase = self.scout.poll(t_s)
            if self.scout.active:
                return self._scouting(t_s, phase)
            self.scout_log.append(self.scout.record)
            stop, self.scout = self.scout, None
            if stop.head_up:      # never resume locomotion with the head raised
                self.abort(f"scout at waypoint {stop.record.waypoint_index}: {stop.record.outcome}")
                d = self.final_decision(t_s)
                d.trajectory_active = True
                return d
            if self.tracker.done:  # the last waypoint's stop is over, the head down: the mission ends
                self.state, self.outcome = DONE, "done: every waypoint reached"
                return self._hold(t_s, self.outcome, stale=False, finished=True)
        limit = self.mission.time_limit_s
        if limit is not None and t_s - self.t_start > limit:
            self.state, self.outcome = TIMEOUT, f"timeout: time limit {limit:g} s reached"
            self._cancel_leg()
            return self._hold(t_s, self.outcome, stale=False, finished=True)
        if self.paused is not None:
            return self._hold(t_s, f"paused: {self.paused} (resume to go on)", stale=False)
        if self._after_leg is not None:
            d = self._after_leg_tick(t_s)
            if d is not None:
                return d
        if self.tracker.waypoint_index in self.mission.legs:
            return self._navigate(t_s, self.tracker.waypoint_index)
        problem = self.pose_problem(t_s)
        if problem:
            if not self._was_stale:
                self.filter.reset()
            self._was_stale = True
            return self._hold(t_s, f"holding: {problem}", stale=True)
        self._was_stale = False
        x, y = self._xy
        cmd = self.tracker.update(x, y, self.filter.value)
        gait = self.mission.gaits[cmd.gait]
        status = dict(waypoint_index=cmd.waypoint_index, num_waypoints=n, waypoint_reached=cmd.reached,
                      distance=cmd.distance, yaw_error_abs=cmd.yaw_error_abs, yaw_error_rel=cmd.yaw_error_rel,
                      yaw_error=cmd.yaw_error, w=cmd.w, mode=cmd.mode, delta=cmd.delta_rad, gait=gait,
                      done=cmd.done, pose_stale=False, note=cmd.action)
        if cmd.reached and cmd.target_index in self.mission.scouts:
            self._start_scout(t_s, cmd.target_index)
            if self.scout is not None:
                return self._scouting(t_s, self.scout.phase)
        finished = cmd.done
        if finished:
            self.state, self.outcome = DONE, "done: every waypoint reached"
        return Decision(t_s, gait, cmd.steer, cmd.delta_rad if cmd.steer else 0.0, status, hold=cmd.done,
                        finished=finished, outcome=self.outcome, command=cmd)

    # -- scout stops (missions/scout.py) -------------------------------------------------------------
    def _start_scout(self, t_s: float, index: int) -> None:
        spec = self.mission.scouts[index]
        if self.scout_planner is None or self.executor is None:
            record = ScoutRecord(index, spec, "failed: no scout planner or trajectory executor on this path")
            self.scout_log.append(record)
            return
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="scout-planner")
        self.scout = ScoutStop(index, spec, self.scout_planner, self.executor, self._pool)
        self.scout.poll(t_s)

    def _scouting(self, t_s: float, phase: str) -> Decision:
        """Locomotion held while a scout stop runs; the time limit waits for the head to be down."""
        d = self._hold(t_s, f"scout at waypoint {self.scout.record.waypoint_index}: {phase}", stale=False)
        d.trajectory_active = self.scout.trajectory_active
        return d

    # -- navigate_to legs (missions/nav_leg.py) --------------------------------------------------------
    def _navigate(self, t_s: float, index: int) -> Decision:
        """One tick of the leg at waypoint `index`: sent at its first tick, then polled."""
        leg = self.mission.legs[index]
        if self.navigator is None:
            self.abort(f"{leg.describe(index)}: no navigator on this path (a leg needs the planner's move_base)")
            return self._leg_decision(t_s, index, self.outcome, finished=True)
        if self._leg_t0 is None:
            self._leg_t0 = t_s
            self.navigator.send(index, leg)
        state, text = self.navigator.poll()
        fresh = self._xy is not None and not self.pose_problem(t_s)
        distance = math.hypot(leg.x_m - self._xy[0], leg.y_m - self._xy[1]) if fresh else NAN
        if state != LEG_SUCCEEDED and leg.radius_m is not None and distance <= leg.radius_m:
            self.navigator.cancel()
            state, text = LEG_SUCCEEDED, f"centre of mass {distance:.2f} m from the goal (radius_m {leg.radius_m:g})"
        if state == LEG_SUCCEEDED:
            self._leg_t0 = None
            self.tracker.skip()
            self.filter.reset()     # the yaw while the planner drove says nothing of the tracker's heading
            if self.tracker.done and index not in self.mission.scouts:
                self.state, self.outcome = DONE, "done: every waypoint reached"
                return self._leg_decision(t_s, index, f"reached: {text}", distance, reached=True)
            self._after_leg = (t_s + self.leg_hold_s, index, f"reached: {text}")
            return self._after_leg_tick(t_s, distance, reached=True)
        if state == LEG_FAILED:
            self._leg_t0 = None     # the goal has ended: nothing to cancel
            self.abort(f"{leg.describe(index)}: {text}")
            return self._leg_decision(t_s, index, text, distance, finished=True)
        if leg.time_limit_s is not None and t_s - self._leg_t0 > leg.time_limit_s:
            self.abort(f"{leg.describe(index)}: time limit {leg.time_limit_s:g} s reached")
            return self._leg_decision(t_s, index, "time limit reached", distance, finished=True)
        return self._leg_decision(t_s, index, text or state, distance)

    def _after_leg_tick(self, t_s: float, distance: float = NAN, reached: bool = False) -> Optional[Decision]:
        """A tick of a reached leg's after-hold: the hold while it lasts; once over, the leg's scout stop
        starts, or None and the tracker goes on at this tick. The reached tick itself always reports the
        leg reached (the run's metrics count it there)."""
        until, index, leg_state = self._after_leg
        holding = t_s < until
        if not holding:
            self._after_leg = None
            if index in self.mission.scouts:
                self._start_scout(t_s, index)
        if holding or reached:
            note = f"{leg_state}; holding {until - t_s:.1f} s before going on" if holding else leg_state
            d = self._leg_decision(t_s, index, note, distance, reached, driving=False)
            d.trajectory_active = self.scout is not None and self.scout.trajectory_active
            return d
        return self._scouting(t_s, self.scout.phase) if self.scout is not None else None

    def _leg_decision(self, t_s: float, index: int, leg_state: str, distance: float = NAN,
                      reached: bool = False, finished: bool = False, driving: bool = True) -> Decision:
        """The decision of a leg's tick: no gait command while the navigator drives, the hold in its
        after-hold (driving False) and when the mission ended."""
        tr, ended = self.tracker, finished or self.state != RUNNING
        navigating = driving and not ended
        note = f"{self.mission.legs[index].describe(index)}: {leg_state}"
        status = dict(waypoint_index=tr.waypoint_index, num_waypoints=len(self.mission.waypoints),
                      waypoint_reached=reached, distance=distance, yaw_error_abs=NAN, yaw_error_rel=NAN,
                      yaw_error=NAN, w=NAN, mode=tr.mode, delta=0.0,
                      gait=NAVIGATE_TO if navigating else self.hold_gait, done=tr.done, pose_stale=False, note=note)
        return Decision(t_s, self.hold_gait, False, 0.0, status, hold=not navigating, finished=ended,
                        outcome=self.outcome if ended else "", navigating=navigating, leg_state=leg_state)

    def _cancel_leg(self) -> None:
        if self._leg_t0 is not None:
            self._leg_t0 = None
            self.navigator.cancel()

    def close(self) -> None:
        """Stop the planner's worker (a plan under way is finished and dropped) and a leg's goal."""
        self._cancel_leg()
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None

    def _hold(self, t_s: float, note: str, stale: bool, finished: bool = False) -> Decision:
        tr = self.tracker
        status = dict(waypoint_index=tr.waypoint_index, num_waypoints=len(self.mission.waypoints),
                      waypoint_reached=False, distance=NAN, yaw_error_abs=NAN, yaw_error_rel=NAN, yaw_error=NAN,
                      w=NAN, mode=tr.mode, delta=tr.delta_rad, gait=self.hold_gait, done=tr.done,
                      pose_stale=stale, note=note)
        return Decision(t_s, self.hold_gait, False, 0.0, status, hold=True, finished=finished,
                        outcome=self.outcome if finished else "")

    def final_decision(self, t_s: float) -> Decision:
        """The hold to send when the mission ends outside a tick (abort, shutdown)."""
        return self._hold(t_s, self.outcome or "stopped", stale=False, finished=True)
