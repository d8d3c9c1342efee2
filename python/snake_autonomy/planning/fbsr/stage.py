"""One FBSR stage: optimise the active joints' cubics, check the result, restart on failure
(paper III.E: "does the ZMP stay inside the polygon for the total length of the given
trajectory? If not, we randomly reseed the spline coefficients ... and re-plan").
"""
import time
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
from scipy.optimize import minimize

from . import collision, spline
from .cost import StageCost, head_clearance, pipe_wall_overlap
from .support import Support


#: Forward-difference step of the cost's gradient (rad).
GRADIENT_STEP_RAD = 1e-4


class PlanningError(RuntimeError):
    """No plan satisfies the checks; the message says which and why."""


@dataclass
class Stage:
    kind: str                    # "raise", "shift" (eq. 1 before a transfer) or "lower"
    active_modules: int
    q_start: np.ndarray          # (N,) joint angles at the start
    delta: np.ndarray            # (active_modules,) end offsets of the active joints
    t_end_s: float
    contacts_xy: np.ndarray      # the base's ground contacts (U is their hull)
    next_contacts_xy: Optional[np.ndarray] = None   # U' before a transfer
    k1: float = 1.0
    restarts: int = 0
    planning_time_s: float = 0.0
    cost_terms: dict = field(default_factory=dict)

    def joints(self, t_s) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t_s, float))
        q = np.repeat(self.q_start[None, :], len(t), axis=0)
        m = self.active_modules
        q[:, :m] = spline.positions(self.q_start[:m], self.delta, self.t_end_s, t)
        return q

    @property
    def q_end(self) -> np.ndarray:
        return self.joints([self.t_end_s])[0]

    def reversed(self) -> "Stage":
        """The same motion backwards: again a cubic of eq. 3-8 (smoothstep is symmetric)."""
        return Stage("lower", self.active_modules, self.q_end, -self.delta, self.t_end_s,
                     self.contacts_xy, None, self.k1, 0, 0.0, {})


def sample_times(t_end_s: float, period_s: float) -> np.ndarray:
    """Times from 0 to t_end inclusive, at most period_s apart."""
    n = int(np.ceil(t_end_s / period_s - 1e-9))
    return np.linspace(0.0, t_end_s, n + 1)


@dataclass
class Checks:
    """The global checks of a stage, on samples period_s apart."""
    within: Support                       # the ZMP stays strictly inside at every sample
    end_within: Optional[Support] = None  # ... and ends inside this one (U ∩ U' for a shift)
    head_above_m: Optional[float] = None  # the head ends higher than this (after a transfer)
    ground_tol_m: float = 0.002
    period_s: float = 0.05
    self_margin_m: float = 0.0            # capsules of non-adjacent modules at least this far apart

    def failures(self, cost: StageCost, delta) -> list:
        pos, com = cost.positions_com(delta, sample_times(cost.t_end_s, self.period_s))
        out = []
        zmp = com[:, :2]
        edge_m = self.within.signed_distance(zmp)
        if np.any(edge_m <= 0):
            out.append(f"ZMP leaves the polygon (worst edge distance {edge_m.min() * 1e3:.1f} mm)")
        if self.end_within is not None and self.end_within.signed_distance(zmp[-1:])[0] <= 0:
            out.append("ZMP ends outside U ∩ U'")
        r = cost.chain.radius_m
        low = float(pos[:, :cost.m, 2].min())
        if low < r - self.ground_tol_m:
            out.append(f"a module goes {1e3 * (r - low):.1f} mm into the floor")
        if cost.pipe is not None and cost.w.k_wall_per_m2 > 0:
            wall = float(pipe_wall_overlap(pos[:, :cost.m], cost.pipe, r,
                                             head_clearance(cost.w.pipe_clearance_m, cost.m)).max())
            if wall > self.ground_tol_m:
                out.append(f"a module goes {1e3 * wall:.1f} mm into the pipe's wall"
                           + (f" (with the {1e3 * cost.w.pipe_clearance_m:.0f} mm pipe clearance)"
                              if cost.w.pipe_clearance_m > 0 else ""))
        clearance, pair = collision.worst_clearance(pos, r)
        if clearance < self.self_margin_m:
            out.append(self_collision_problem(clearance, pair, self.self_margin_m))
        head_z = float(pos[-1, 0, 2])
        if self.head_above_m is not None and head_z <= self.head_above_m:
            out.append(f"head ends at {head_z:.3f} m, not above {self.head_above_m:.3f} m")
        return out


def self_collision_problem(clearance_m: float, pair, margin_m: float) -> str:
    """The reason a posture's modules are too close, in words."""
    how = (f"overlap by {-1e3 * clearance_m:.1f} mm" if clearance_m < 0
           else f"come {1e3 * clearance_m:.1f} mm apart")
    return (f"modules {pair[0]} and {pair[1]} {how} (self-collision: capsules at least "
            f"{1e3 * margin_m:.1f} mm apart)")


def optimise(cost: StageCost, checks: Checks, rng: np.random.Generator, max_restarts: int,
             joint_margin_rad: float, kind: str, contacts_xy, next_contacts_xy=None,
             k1: float = 1.0, restarts_enabled: bool = True, random_first: bool = False,
             keep_best: bool = False) -> Stage:
    """The best stage for `cost` that passes `checks`, with random restarts; PlanningError if
    none does within max_restarts. random_first: the first attempt starts at random too.
    keep_best: every attempt runs and the passing one of least cost wins (else the first that
    passes)."""
    m = cost.m
    chain = cost.chain
    lo, hi = spline.delta_bounds(cost.q_start[:m], chain.lower[:m], chain.upper[:m],
                                 joint_margin_rad)
    bounds = list(zip(lo, hi))
    started = time.perf_counter()
    problems = []
    best = None
    attempts = 1 + (max_restarts if restarts_enabled else 0)
    for attempt in range(attempts):
        if attempt == 0 and not random_first:
            x0 = np.clip(rng.normal(0.0, 0.02, m), lo, hi)
        else:
            x0 = rng.uniform(lo, hi) * 0.5
        # the gradient by forward differences (the step scipy used), batched in one FK call
        res = minimize(cost.value_and_gradient, x0, args=(GRADIENT_STEP_RAD, lo, hi), jac=True,
                       method="L-BFGS-B", bounds=bounds, options={"maxiter": 200})
        problems = checks.failures(cost, res.x)
        if not problems and (best is None or res.fun < best[0]):
            best = (float(res.fun), np.asarray(res.x, float), attempt)
        if best is not None and not keep_best:
            break
    if best is not None:
        _, x, attempt = best
        return Stage(kind, m, cost.q_start.copy(), x, cost.t_end_s, np.asarray(contacts_xy, float),
                     next_contacts_xy, k1, attempt, time.perf_counter() - started, cost.terms(x))
    raise PlanningError(f"{kind} stage with {m} active modules: no trajectory passes the checks "
                        f"after {attempts} attempts ({'; '.join(problems)})")
