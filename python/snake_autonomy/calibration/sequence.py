"""The calibration run, one sequence for both back-ends: open-loop sidewinding at each δ, then hold.

    plan = Plan(deltas_deg=[-2, 0, 2, 4], period_s=1 / 0.35, settle_cycles=3, record_cycles=6)
    outcome = run_plan(robot, plan, pose_timeout_s=0.5)
    outcome.segments          # analysis.Segment per δ completed
    outcome.stopped           # "" when every δ ran; else why it stopped early

`robot` is anything with
    command(gait: str, steer: bool, delta_rad: float) -> str   # "" accepted, else the refusal
    next_pose(timeout_s: float) -> Optional[(t_s, x_m, y_m, yaw_rad)]   # com_pose; None: none came
the simulated robot (sim_backend.SimRobot, lock-step) or the robot through ROS (ros_backend.RosRobot).

Safety: nothing moves before a first pose arrived (within start_timeout_s). The gait command is
re-sent every resend_s of pose time (the driver's command lifetime). The robot is commanded to hold
(the driver's `hold` gait) at the end, when the pose goes stale (no pose for pose_timeout_s), when a
command is refused, when the robot does not move (the driver not running: fault, torque off), on
Ctrl-C (KeyboardInterrupt) and on any error (a RuntimeError, the driver's fault or a roll-over,
ends the run like a stale pose; others propagate after the hold); the segments completed so far are
kept. Time is the poses' own (simulated time, or the stamps of com_pose), so settling and recording
windows mean the same on both back-ends.
"""
import math
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Sequence

import numpy as np

from .analysis import Segment

HOLD_GAIT = "hold"


@dataclass
class Plan:
    deltas_deg: Sequence[float]
    period_s: float                      # the gait's period (config/gaits.yaml frequency)
    gait: str = "sidewind"
    settle_cycles: float = 3.0           # after each new δ, not recorded
    record_cycles: int = 6               # recorded per δ
    resend_s: float = 0.5                # gait command heartbeat
    min_travel_m_per_cycle: float = 0.02  # less over the recorded cycles: the robot is not moving
    run: str = ""                        # label of this run (seed, session)

    def check(self) -> None:
        problems = []
        if len(self.deltas_deg) < 2 or len(set(self.deltas_deg)) < 2:
            problems.append(f"deltas: need two different values or more, got {list(self.deltas_deg)}")
        if not all(math.isfinite(d) for d in self.deltas_deg):
            problems.append(f"deltas: must be finite, got {list(self.deltas_deg)}")
        if not self.period_s > 0:
            problems.append(f"period_s: must be > 0, got {self.period_s}")
        if not self.settle_cycles >= 0:
            problems.append(f"settle_cycles: must be >= 0, got {self.settle_cycles}")
        if not (isinstance(self.record_cycles, int) and self.record_cycles >= 1):
            problems.append(f"record_cycles: must be an integer >= 1, got {self.record_cycles}")
        if problems:
            raise ValueError("; ".join(problems))

    @property
    def segment_s(self) -> float:
        return (self.settle_cycles + self.record_cycles) * self.period_s


@dataclass
class Outcome:
    segments: List[Segment] = field(default_factory=list)
    stopped: str = ""                    # why the run ended early ("" when complete)


def run_plan(robot, plan: Plan, pose_timeout_s: float = 0.5, start_timeout_s: float = 5.0,
             log: Callable[[str], None] = print) -> Outcome:
    plan.check()
    out = Outcome()
    try:
        if robot.next_pose(start_timeout_s) is None:
            out.stopped = f"no pose within {start_timeout_s:g} s: nothing was commanded"
            return out
        for delta in plan.deltas_deg:
            segment, why = _one_delta(robot, plan, float(delta), pose_timeout_s, log)
            if segment is not None:
                out.segments.append(segment)
            if why:
                out.stopped = why
                break
    except KeyboardInterrupt:
        out.stopped = "interrupted (Ctrl-C)"
    except RuntimeError as exc:          # the driver faulted, the simulated robot rolled over
        out.stopped = str(exc)
    finally:                             # whatever happened, including errors that propagate
        robot.command(HOLD_GAIT, False, 0.0)
        log(f"holding ({out.stopped or 'done'})")
    return out


def _one_delta(robot, plan: Plan, delta_deg: float, pose_timeout_s: float, log):
    """(Segment or None, why it stopped or "")."""
    delta_rad = math.radians(delta_deg)
    why = robot.command(plan.gait, True, delta_rad)
    if why:
        return None, f"the driver refused {plan.gait} at delta {delta_deg:+g} deg: {why}"
    log(f"{plan.gait} at delta {delta_deg:+g} deg: {plan.settle_cycles:g} cycles settling, "
        f"{plan.record_cycles} recorded ({plan.segment_s:.0f} s)")
    settle_s = plan.settle_cycles * plan.period_s
    record_s = plan.record_cycles * plan.period_s
    t0: Optional[float] = None
    last_sent = None
    samples = []
    while True:
        pose = robot.next_pose(pose_timeout_s)
        if pose is None:
            return None, f"stale pose: none for {pose_timeout_s:g} s at delta {delta_deg:+g} deg"
        t = float(pose[0])
        if t0 is None:
            t0 = last_sent = t
        if t - last_sent >= plan.resend_s:
            why = robot.command(plan.gait, True, delta_rad)
            if why:
                return None, f"the driver refused {plan.gait} at delta {delta_deg:+g} deg: {why}"
            last_sent = t
        if t - t0 >= settle_s - 1e-9:
            samples.append(tuple(float(v) for v in pose[:4]))
        if t - t0 >= settle_s + record_s - 1e-9:
            xy = np.array([s[1:3] for s in samples])
            travel = float(np.hypot(*(xy[-1] - xy[0])))
            if travel < plan.min_travel_m_per_cycle * plan.record_cycles:
                return None, (f"the robot did not move at delta {delta_deg:+g} deg ({travel:.3f} m in "
                              f"{plan.record_cycles} cycles): is the driver running (its state is on /diagnostics)?")
            return Segment(delta_deg, plan.period_s, np.array(samples), plan.run), ""
