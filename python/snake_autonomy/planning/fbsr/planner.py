"""The FBSR loop (paper II and III.E): raise, check the end condition, shift the ZMP into U ∩ U'
with decreasing K1 (dynamic weighting), transfer two modules from the base, repeat; and the
inverse, lowering the head back to the lying posture.

Yaw joints: every joint of the active portion is optimised, pitch or yaw. Lying flat, only the
pitch joints can lift a module (a yaw joint then turns about the vertical); the yaw joints of the
active portion move the ZMP sideways and, once their module is tilted, add to the height. The
base's joints, pitch and yaw, keep the lying posture's angles.

Self-collision: the lying posture and every sample of every stage keep the capsules of
non-adjacent modules self_collision_margin_m apart (collision.py; a cost term pushes, the stage
check refuses); a plan that cannot is refused with the modules and the distance. The last raise
to the highest head (every module active, no height or target asked) runs all its restarts and
keeps the best that passes: its first local optimum often leaves the head well below what the
same modules reach; then up to max_final_cycles more raises from where it ended, each kept only
when the head ends higher.

The pipe (paper fig. 6): the head aims under the mouth, and once under it, the next raise (with
the same modules) aims 5 cm inside; with every module active, up to max_final_cycles more raises
(the best of each's restarts, without the pipe potential, which pulls every module to the axis
against the head's way in). The plan ends once the head is PIPE_DEPTH_M past the mouth and
pipe_clearance_m inside the bore's edge (the bore: the pipe's radius less a module's); on the way
in, the head keeps that clearance from the edge above the lip (cost.pipe_wall_overlap). The
clearance is room for the sag: under load the arm ends some 15 mm sideways of its plan, and a head
planned 1.6 mm inside the edge caught on the lip. A plan whose last raise leaves the head elsewhere
is refused with where it ended and the clearance.
"""
import time
from dataclasses import dataclass, field
from typing import Callable, List, Optional

import numpy as np
from threadpoolctl import threadpool_limits

from . import collision
from .chain import Chain, lying_posture
from .config import PlannerConfig, RobotPosture
from .cost import Directive, Pipe, StageCost, Weights
from .pipe_scene import head_in_mouth
from .stage import Checks, PlanningError, Stage, optimise, self_collision_problem
from .support import Support, convex_hull


@dataclass
class Plan:
    robot_name: str
    chain: Chain
    stages: List[Stage]
    restarts: int = 0
    planning_time_s: float = 0.0
    stage_times_s: List[float] = field(default_factory=list)

    @property
    def q_end(self) -> np.ndarray:
        return self.stages[-1].q_end if self.stages else self.chain.q_lying

    @property
    def final_head_height_m(self) -> float:
        return float(self.chain.pose(self.q_end).head[2])

    @property
    def active_modules(self) -> int:
        return self.stages[-1].active_modules if self.stages else 0

    @property
    def duration_s(self) -> float:
        return float(sum(s.t_end_s for s in self.stages))


#: A plan into the pipe ends with the head at least this far above the mouth, within the bore.
PIPE_DEPTH_M = 0.02


class FbsrPlanner:
    def __init__(self, robot, planner: PlannerConfig, posture: RobotPosture,
                 torque_limit_nm: float = 9.9):
        self.robot = robot
        self.cfg = planner
        self.posture = posture
        q_lying = lying_posture(robot, np.radians(posture.pitch_offset_deg),
                                np.radians(posture.yaw_body_deg), np.radians(posture.yaw_tail_deg),
                                posture.tail_curl_joints)
        self.chain = Chain(robot, q_lying)
        self.torque_limit_nm = torque_limit_nm
        self.on_stage: Optional[Callable[[Stage], None]] = None   # called with each stage added to a plan

    # ---- the supports --------------------------------------------------------------------------
    def support(self, active_modules: int, other: Optional[Support] = None) -> Support:
        """U of the base left by `active_modules`, shrunk by the margin (∩ other if given)."""
        return Support.of(self.chain.base_contacts(active_modules), self.cfg.margin_m, other)

    def max_modules(self) -> int:
        """Most active modules whose base still has a support polygon (3 contacts spanning area)."""
        m = self.chain.num_modules
        while m > 0 and (convex_hull(self.chain.base_contacts(m)).is_empty
                         or self.support(m).empty):
            m -= 1
        return m

    # ---- the loop ------------------------------------------------------------------------------
    def plan(self, max_active: Optional[int] = None, height_m: Optional[float] = None,
             pipe: Optional[Pipe] = None, seed: int = 0, restarts: bool = True,
             target_m=None) -> Plan:
        # One BLAS thread: L-BFGS-B makes many BLAS calls on vectors of a few elements, and
        # OpenBLAS's second thread spin-waits on them; on a busy machine that cost 4x (bench/).
        with threadpool_limits(limits=1, user_api="blas"):
            return self._plan(max_active, height_m, pipe, seed, restarts, target_m)

    def _plan(self, max_active, height_m, pipe, seed, restarts, target_m) -> Plan:
        cfg = self.cfg
        rng = np.random.default_rng(seed)
        max_active = self.posture.max_active if max_active is None else int(max_active)
        limit = self.max_modules()
        if not 1 <= max_active <= limit:
            raise PlanningError(f"--max-active {max_active}: {self.robot.name} can have 1 to "
                                f"{limit} active modules (its base needs contacts spanning an area)")
        if pipe is not None:
            self._check_pipe(pipe)
        into_pipe = pipe is not None and target_m is None and height_m is None
        if into_pipe:
            # The head goes into the mouth from below: first under it, then in.
            target_m = np.asarray(pipe.entry_point(), float)
            below = np.asarray(pipe.entry_point(-2.0 * self.chain.radius_m), float)
            bore_m = pipe.radius_m - self.chain.radius_m - cfg.pipe_clearance_m
        directive = Directive(height_m=height_m, target_m=target_m)
        m = min(self.posture.initial_active, max_active)
        q = self.chain.q_lying.copy()
        if not self.support(m).contains_point(self.chain.pose(q).zmp):
            raise PlanningError(f"{self.robot.name}: the lying posture's ZMP is not inside the "
                                f"support polygon of {m} active modules")
        clearance, pair = collision.worst_clearance(self.chain.pose(q).positions, self.chain.radius_m)
        if clearance < cfg.self_collision_margin_m:
            raise PlanningError(f"{self.robot.name}: the lying posture: "
                                + self_collision_problem(clearance, pair, cfg.self_collision_margin_m))
        plan = Plan(self.robot.name, self.chain, [])
        started = time.perf_counter()
        head_before = self.chain.pose(q).head[2]
        transferred = False
        backtracks = 0
        extra_cycles = 0
        entered_at = None        # the active modules with which a raise from under the mouth was tried
        reseed = False
        previous = None          # where the last raise started: (stages, q, m, head, transferred, raised)
        raised = -np.inf         # the highest head at the end of a raise so far
        while True:
            u = self.support(m)
            first = len(plan.stages)
            here = (first, q, m, head_before, transferred, raised)
            if into_pipe:
                head_now = self.chain.pose(q).head
                under = np.hypot(*(head_now[:2] - below[:2])) < bore_m
                directive = Directive(target_m=target_m if under else below)
            q_before = q
            try:
                # The global check after a transfer (paper III.E): the head ends higher than
                # before it. The last raise (every module active) must also end above the highest
                # raise so far: the shifts lower the head, and a last raise that recovers only part
                # of that is a local optimum (re-planned from a random start).
                # Aiming at a point (the pipe), the head may have to come down to get under it.
                highest = m >= max_active and target_m is None and height_m is None
                floor = max(head_before, raised) if highest else head_before
                stage = self._stage("raise", m, q, u, Checks(
                    u, head_above_m=floor if transferred else None,
                    period_s=cfg.sample_period_s, self_margin_m=cfg.self_collision_margin_m),
                    directive, pipe, rng, cfg.k1, restarts, random_first=reseed,
                    keep_best=m >= max_active and height_m is None)
            except PlanningError:
                # No raise from here passes the checks: re-plan the previous raise (and the
                # transfer after it) from a random start, at most max_backtracks times.
                if not restarts or previous is None or backtracks >= cfg.max_backtracks:
                    raise
                backtracks += 1
                first, q, m, head_before, transferred, raised = previous
                del plan.stages[first:]
                previous, reseed = None, True
                continue
            previous = here
            reseed = False
            self._add(plan, stage)
            q = stage.q_end
            head_xyz = self.chain.pose(q).head
            head = head_xyz[2]
            raised = max(raised, head)
            if height_m is not None and head >= height_m - cfg.head_height_tol_m:
                break
            if target_m is not None and np.linalg.norm(head_xyz - np.asarray(target_m)) < cfg.target_tol_m:
                break
            if into_pipe and head_in_mouth(head_xyz, pipe, self.chain.radius_m, PIPE_DEPTH_M,
                                           cfg.pipe_clearance_m):
                break                   # in the bore (a later cycle aiming closer may come out again)
            if into_pipe and directive.target_m is below and entered_at != m and \
                    np.hypot(*(head_xyz[:2] - below[:2])) < bore_m:
                entered_at = m          # under the mouth: the next raise, with the same modules, goes in
                continue
            if m >= max_active and target_m is not None and extra_cycles < cfg.max_final_cycles:
                extra_cycles += 1       # paper II: plan again until the end condition or a
                continue                # cycle limit; no module left to transfer
            if m >= max_active:
                if height_m is not None:
                    raise PlanningError(
                        f"--height-m {height_m}: no plan reaches it with at most {max_active} "
                        f"active modules of {self.robot.name} (highest found: {head:.3f} m)")
                if into_pipe:
                    raise PlanningError(self._pipe_missed(pipe, head_xyz, max_active))
                if target_m is None:
                    self._raise_higher(plan, m, u, directive, rng, restarts)
                break
            m_next = min(m + 2, max_active)
            try:
                q = self._prepare_transfer(plan, m, m_next, q, directive, pipe, rng, restarts)
            except PlanningError:
                # No shift into U ∩ U' from where this raise ended: re-plan the raise from a
                # random start (a restart across stages), at most max_backtracks times.
                if not restarts or backtracks >= cfg.max_backtracks:
                    raise
                backtracks += 1
                del plan.stages[first:]
                q, reseed = q_before, True
                continue
            head_before = self.chain.pose(q).head[2]
            transferred = True
            m = m_next
        plan.planning_time_s = time.perf_counter() - started
        plan.stage_times_s = [st.planning_time_s for st in plan.stages]
        plan.restarts = sum(st.restarts for st in plan.stages) + backtracks
        return plan

    def _raise_higher(self, plan, m, u, directive, rng, restarts) -> None:
        """Going as high as it can: up to max_final_cycles more raises with every module active,
        each from where the last ended and kept only when the head ends head_height_tol_m higher
        (the best of its restarts); the first that does not ends the plan. One raise's optimum
        depends on where it starts: this is how no seed stays well below the others."""
        cfg = self.cfg
        for _ in range(cfg.max_final_cycles):
            q = plan.q_end
            above = self.chain.pose(q).head[2] + cfg.head_height_tol_m
            try:
                stage = self._stage("raise", m, q, u, Checks(
                    u, head_above_m=above, period_s=cfg.sample_period_s,
                    self_margin_m=cfg.self_collision_margin_m),
                    directive, None, rng, cfg.k1, restarts, random_first=True, keep_best=True)
            except PlanningError:
                return
            self._add(plan, stage)

    def _prepare_transfer(self, plan, m, m_next, q, directive, pipe, rng, restarts):
        """Eq. 1: re-plan with decreasing K1 until the ZMP is in U ∩ U'."""
        cfg = self.cfg
        u = self.support(m)
        target = self.support(m_next, u)
        if target.empty:
            raise PlanningError(f"U ∩ U' is empty going from {m} to {m_next} active modules")
        k1 = cfg.k1
        failed_s = 0.0        # time of the re-plans that failed, counted in the next stage's
        for _ in range(cfg.max_shift_replans):
            if target.contains_point(self.chain.pose(q).zmp):
                return q
            k1 = max(0.0, k1 - cfg.k1_step)
            checks = Checks(u, end_within=target, period_s=cfg.sample_period_s,
                            self_margin_m=cfg.self_collision_margin_m)
            started = time.perf_counter()
            try:
                stage = self._stage("shift", m, q, target, checks, directive, pipe, rng, k1,
                                    restarts, next_contacts=self.chain.base_contacts(m_next),
                                    max_restarts=cfg.shift_restarts)
            except PlanningError:
                failed_s += time.perf_counter() - started
                continue          # lower K1 further
            stage.planning_time_s += failed_s
            failed_s = 0.0
            self._add(plan, stage)
            q = stage.q_end
        if target.contains_point(self.chain.pose(q).zmp):
            return q
        raise PlanningError(f"cannot shift the ZMP into U ∩ U' before moving from {m} to "
                            f"{m_next} active modules (K1 lowered to {k1:.2f})")

    def _stage(self, kind, m, q, support, checks, directive, pipe, rng, k1, restarts,
               next_contacts=None, max_restarts=None, random_first=False, keep_best=False) -> Stage:
        cfg = self.cfg
        # The pipe's pull is a directive too: a shift lowers K3 in proportion with K1.
        k3 = cfg.k3 * (k1 / cfg.k1 if cfg.k1 > 0 else 1.0) if pipe is not None else 0.0
        if keep_best and pipe is not None:
            k3 = 0.0    # going in: the potential pulls every module to the axis, against the head's way in
        weights = Weights(k1=k1, k2=cfg.k2, k3=k3,
                          k_torque=cfg.k_torque, ks_per_m2=cfg.ks_per_m2,
                          k_out_per_m2=cfg.k_out_per_m2, k_wall_per_m2=cfg.k_wall_per_m2,
                          k_clearance_per_m2=cfg.k_self_collision_per_m2,
                          self_margin_m=cfg.self_collision_margin_m,
                          self_push_m=cfg.self_collision_push_m,
                          pipe_clearance_m=cfg.pipe_clearance_m)
        cost = StageCost(self.chain, q, m, support, weights, directive, cfg.stage_duration_s,
                         cfg.cost_samples, pipe, self.torque_limit_nm)
        max_restarts = cfg.max_restarts if max_restarts is None else max_restarts
        return optimise(cost, checks, rng, max_restarts, np.radians(cfg.joint_margin_deg),
                        kind, self.chain.base_contacts(m), next_contacts, k1, restarts,
                        random_first, keep_best)

    def _add(self, plan: Plan, stage: Stage) -> None:
        plan.stages.append(stage)
        plan.restarts += stage.restarts
        plan.stage_times_s.append(stage.planning_time_s)
        if self.on_stage is not None:
            self.on_stage(stage)

    def _pipe_missed(self, pipe: Pipe, head_xyz, max_active: int) -> str:
        """Why a plan into the pipe is refused: where its last raise left the head."""
        d = float(np.hypot(head_xyz[0] - pipe.x_m, head_xyz[1] - pipe.y_m))
        c = self.cfg.pipe_clearance_m
        return (f"--pipe {pipe.x_m:g},{pipe.y_m:g},{pipe.radius_m:g}: no plan found puts the head into the "
                f"pipe with at most {max_active} active modules of {self.robot.name} (the last raise "
                f"ended {d:.3f} m from the axis at {head_xyz[2]:.3f} m; the plan must end it within "
                f"{pipe.radius_m - self.chain.radius_m - c:.3f} m of the axis: the bore's "
                f"{pipe.radius_m - self.chain.radius_m:.3f} m less pipe_clearance_m {c:g} m, at least "
                f"{PIPE_DEPTH_M:.3f} m above the mouth at {pipe.mouth_m:g} m)")

    def _check_pipe(self, pipe: Pipe) -> None:
        if not pipe.radius_m > self.chain.radius_m:
            raise PlanningError(f"--pipe radius {pipe.radius_m} m: must exceed the module "
                                f"radius {self.chain.radius_m} m for the head to enter")
        if not pipe.radius_m > self.chain.radius_m + self.cfg.pipe_clearance_m:
            raise PlanningError(f"--pipe radius {pipe.radius_m} m: leaves no room for the head with "
                                f"pipe_clearance_m {self.cfg.pipe_clearance_m:g} m from the bore's edge "
                                f"(module radius {self.chain.radius_m} m)")
        lying = self.chain.pose(self.chain.q_lying).positions[:, :2]
        d = np.hypot(lying[:, 0] - pipe.x_m, lying[:, 1] - pipe.y_m)
        if np.any(d < pipe.radius_m + self.chain.radius_m):
            raise PlanningError(f"--pipe {pipe.x_m},{pipe.y_m},{pipe.radius_m}: the pipe is inside "
                                f"the lying robot (a module is {d.min():.3f} m from its axis)")


def lowering(plan: Plan) -> Plan:
    """The inverse: from the plan's last posture back to the lying posture, along the same stages
    backwards. Each reversed stage is again a cubic of eq. 3-8 and passes through the same ZMPs in
    the same support polygons, so the checks the raise passed hold for it too."""
    stages = [s.reversed() for s in reversed(plan.stages)]
    return Plan(plan.robot_name, plan.chain, stages)
