"""The mission action `scout`, ROS-free: at a waypoint, raise the head, hold, lower, resume.

In a mission file a waypoint may be a mapping with a scout stop::

    waypoints:
      - [0.5, 0.0, 0]
      - {pose: [1.0, 0.0, 0], scout: {height_m: 0.3, hold_s: 5}}

scout keys: ``height_m`` (head height, m; absent: as high as the robot's active portion allows),
``hold_s`` (time held raised, s), ``max_active`` (most active modules; absent: config/scout.yaml's),
``seed`` (planner seed). Checked by `parse_scout` with the rest of the mission (every problem listed).

The sequence (`ScoutStop`), driven by MissionRunner's control tick once the waypoint is reached:

    planning (a worker thread, off the control loop; the robot holds its gait)
      -> the plan failed a check: the failure is recorded, nothing is sent, the mission resumes
    -> raising (the raise's trajectory handed to the executor; refused: recorded, resume)
    -> holding (hold_s after the executor reports the raise finished)
    -> lowering (the inverse plan back to the lying posture)
    -> done: the mission resumes locomotion.
    A raise or lowering that ends without reaching its last point (the executor's `aborted`: the driver
    aborted or refused it, or no final status came in time), and a lowering the executor refuses, may
    leave the head up: the stop fails and the mission is aborted (never resumed), no gait command sent
    (the driver holds where the trajectory left the joints).

The planner (`ScoutPlanner`, a callable ScoutSpec -> ScoutPlan) does every check before anything
moves: the FBSR planner's own (ZMP inside U at every sample, joint limits, head above after a
transfer), the plan.json contract's (plan_io.problems) and the driver's velocity limit on both
trajectories. The executor (`TrajectoryExecutor`) is the path to the joints: the batch simulator's
`runs.scout_executor.DriverTrajectoryExecutor` (the driver's trajectory
execution in the batch simulator), the ROS side's `nodes.scout_trajectory.TopicTrajectoryExecutor`.
"""
import math
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Protocol

from ..planning.fbsr import plan_io
from .fields import is_number, keyed_mapping
from ..planning.fbsr.build import build_planner
from ..planning.fbsr.planner import lowering
from ..planning.fbsr.trajectory import driver_velocity_limit, lead_in_s, plan_points, velocity_problems

PLANNING, RAISING, HOLDING, LOWERING, DONE, FAILED = "planning", "raising", "holding", "lowering", "done", "failed"
#: Phases in which a trajectory owns the joints: no gait command may be sent.
TRAJECTORY_PHASES = (RAISING, HOLDING, LOWERING)
SCOUT_KEYS = ("height_m", "hold_s", "max_active", "seed")
MAX_HEIGHT_M = 5.0
MAX_HOLD_S = 3600.0
#: A trajectory's end is waited for at most its duration (the last point's time_from_start) + this many
#: seconds: the default of the mission node's ~scout_result_margin_s (nodes/scout_trajectory.py) and of
#: the physics run's send_through_driver (runs/scout_execute.py).
RESULT_MARGIN_S = 5.0


@dataclass(frozen=True)
class ScoutSpec:
    height_m: Optional[float] = None
    hold_s: float = 0.0
    max_active: Optional[int] = None
    seed: int = 0


@dataclass
class ScoutPlan:
    raise_trajectory: Any               # planning.fbsr.trajectory.JointTrajectoryPoints
    lower_trajectory: Any
    planned_head_height_m: float = math.nan
    planning_time_s: float = 0.0
    active_modules: int = 0


class TrajectoryExecutor(Protocol):
    def execute(self, trajectory, t_s: float) -> str:
        """Start `trajectory` at t_s; '' when accepted, otherwise why it was refused."""

    #: Why the last trajectory sent ended without reaching its last point ('' while it runs or when it did).
    aborted: str

    def finished(self, t_s: float) -> bool:
        """The last trajectory sent has ended: reached its last point (then held), or not (`aborted`
        says why). Becomes True in bounded time: an executor that can lose a trajectory gives up on it
        after a deadline and says so in `aborted`."""

    def head_height_m(self) -> float:
        """The head's height above the floor as the executor's side measures it now (the robot's pose
        source on the ROS side); NaN when it has none. Sampled while held: the record's lowest."""


ScoutPlanner = Callable[[ScoutSpec], ScoutPlan]


def parse_scout(raw, where: str, problems: List[str]) -> Optional[ScoutSpec]:
    """A ScoutSpec from a waypoint's `scout:` mapping; every problem appended, naming key and value."""
    before = len(problems)
    if not keyed_mapping(raw, where, SCOUT_KEYS, problems):
        return None
    h = raw.get("height_m")
    if h is not None and not (is_number(h) and 0 < h <= MAX_HEIGHT_M):
        problems.append(f"{where}.height_m: must be a number in (0, {MAX_HEIGHT_M:g}] m, got {h!r}")
    hold = raw.get("hold_s", 0.0)
    if not (is_number(hold) and 0 <= hold <= MAX_HOLD_S):
        problems.append(f"{where}.hold_s: must be a number in [0, {MAX_HOLD_S:g}] s, got {hold!r}")
    for key, low in (("max_active", 1), ("seed", 0)):
        v = raw.get(key)
        if v is not None and not (isinstance(v, int) and not isinstance(v, bool) and v >= low):
            problems.append(f"{where}.{key}: must be an integer >= {low}, got {v!r}")
    if len(problems) > before:
        return None
    return ScoutSpec(float(h) if h is not None else None, float(hold), raw.get("max_active"), int(raw.get("seed", 0)))


@dataclass
class ScoutRecord:
    """What happened at one scout stop (the mission's log)."""
    waypoint_index: int
    spec: ScoutSpec
    outcome: str = ""                        # "done" or "failed: <why>"
    planned_head_height_m: float = math.nan
    planning_time_s: float = math.nan
    measured_head_height_m: float = math.nan                 # the lowest while held (batch: the plant's)
    phases: Dict[str, float] = field(default_factory=dict)   # phase -> mission time it began

    def as_dict(self) -> dict:
        """JSON-ready: values not known (NaN: no plan, no measurement on this path) become None."""
        def known(v):
            return None if isinstance(v, float) and math.isnan(v) else v
        return {"waypoint_index": self.waypoint_index, "height_m": self.spec.height_m, "hold_s": self.spec.hold_s,
                "outcome": self.outcome, "planned_head_height_m": known(self.planned_head_height_m),
                "planning_time_s": known(self.planning_time_s),
                "measured_head_height_m": known(self.measured_head_height_m), "phases": dict(self.phases)}


class ScoutStop:
    """One scout stop's sequence; `poll(t_s)` at every control tick returns the phase."""

    def __init__(self, waypoint_index: int, spec: ScoutSpec, planner: ScoutPlanner,
                 executor: TrajectoryExecutor, pool: ThreadPoolExecutor):
        self.record = ScoutRecord(waypoint_index, spec)
        self.planner, self.executor = planner, executor
        self.phase = PLANNING
        self.plan: Optional[ScoutPlan] = None
        self._future: Future = pool.submit(self._plan_timed, spec)
        self._hold_until = math.inf
        self._trajectory_sent = False       # a raise or lowering was handed over: the head may be up

    def _plan_timed(self, spec):
        started = time.perf_counter()
        plan = self.planner(spec)
        return plan, time.perf_counter() - started

    def wait_planned(self, timeout_s: float) -> bool:
        """Block until the planner has finished (or timeout_s): True when it has. For lock-step
        simulation (planning then takes no simulated time) and tests; never on a control loop."""
        try:
            self._future.exception(timeout=timeout_s)
        except TimeoutError:
            return False
        return True

    @property
    def active(self) -> bool:
        return self.phase not in (DONE, FAILED)

    @property
    def head_up(self) -> bool:
        """Failed after a trajectory was handed over: the head may be up."""
        return self.phase == FAILED and self._trajectory_sent

    @property
    def trajectory_active(self) -> bool:
        return self.phase in TRAJECTORY_PHASES

    def poll(self, t_s: float) -> str:
        rec = self.record
        rec.phases.setdefault(self.phase, t_s)
        if self.phase == PLANNING and self._future.done():
            try:
                self.plan, wall_s = self._future.result()
            except Exception as err:  # noqa: BLE001 - any planner failure: never sent, recorded
                return self._fail(t_s, f"plan: {err}")
            rec.planned_head_height_m = self.plan.planned_head_height_m
            rec.planning_time_s = wall_s
            self._send(t_s, self.plan.raise_trajectory, RAISING)
        elif self.phase == RAISING and self.executor.finished(t_s):
            if self.executor.aborted:
                return self._fail(t_s, f"{RAISING}: {self.executor.aborted}")
            self._enter(t_s, HOLDING)
            self._hold_until = t_s + rec.spec.hold_s
        elif self.phase == HOLDING:
            self._measure_head()
            if t_s >= self._hold_until:
                self._send(t_s, self.plan.lower_trajectory, LOWERING)
        elif self.phase == LOWERING and self.executor.finished(t_s):
            if self.executor.aborted:
                return self._fail(t_s, f"{LOWERING}: {self.executor.aborted}")
            self._enter(t_s, DONE)
            rec.outcome = DONE
        return self.phase

    def _measure_head(self) -> None:
        """The lowest head height the executor measures while the raise is held (none: stays NaN)."""
        z = self.executor.head_height_m()
        if math.isfinite(z):
            rec = self.record
            rec.measured_head_height_m = z if math.isnan(rec.measured_head_height_m) \
                else min(rec.measured_head_height_m, z)

    def _send(self, t_s, trajectory, phase) -> None:
        why = self.executor.execute(trajectory, t_s)
        if why:
            self._fail(t_s, f"{phase}: the executor refused the trajectory ({why})")
        else:
            self._trajectory_sent = True
            self._enter(t_s, phase)

    def _enter(self, t_s, phase) -> None:
        self.phase = phase
        self.record.phases.setdefault(phase, t_s)

    def _fail(self, t_s, why: str) -> str:
        self.record.outcome = f"failed: {why}"
        self._enter(t_s, FAILED)
        return self.phase


def fbsr_scout_planner(robot_arg: str, scout_config=None, driver_yaml=None, *,
                       torque_limit_nm: float) -> ScoutPlanner:
    """A ScoutPlanner with the FBSR planner for a robot (name or YAML): plan, every check, the raise
    and lowering trajectories. Raises with the reason when any check fails."""

    planner, cfg = build_planner(robot_arg, scout_config, torque_limit_nm=torque_limit_nm)
    vmax = driver_velocity_limit(driver_yaml)
    period = cfg.planner.sample_period_s
    chain = planner.chain

    def plan_scout(spec: ScoutSpec) -> ScoutPlan:
        plan = planner.plan(max_active=spec.max_active, height_m=spec.height_m, seed=spec.seed)
        problems = plan_io.problems(plan_io.to_dict(plan, period))
        # The raise starts from wherever the gait left the joints: the lead-in covers any posture.
        up = plan_points(plan, period, lead_in_s(chain.lower, chain.upper, vmax))
        down = plan_points(lowering(plan), period)
        problems += [f"raise: {p}" for p in velocity_problems(up, vmax)]
        problems += [f"lower: {p}" for p in velocity_problems(down, vmax, up.final_positions_rad)]
        if problems:
            raise ValueError("; ".join(problems))
        return ScoutPlan(up, down, plan.final_head_height_m, plan.planning_time_s, plan.active_modules)

    return plan_scout
