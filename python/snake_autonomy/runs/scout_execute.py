"""A plan run in the MuJoCo plant, checked from the contact forces: metrics.json of the contract

    {"tipped": bool, "outcome": "ok" | "tipped" | "missed_height" | "missed_pipe", "cop_inside_fraction": float,
     "final_head_height_m": float, "planned_head_height_m": float, "max_torque_ratio": float,
     "active_modules": int}

- The start: the plant's robot lying in the plan's first posture (q0_rad, its head placed where
  the planner's world puts it), left to settle with the servos holding it.
- Execution: through the driver, as on the robot: the plan as a joint trajectory
  (trajectory.plan_points) handed to the batch simulator's DriverController (runs/batch.py
  LockStepDriver: the C++ loop driver_node runs, over an in-process servo bus on this plant) by
  `command_trajectory`; the driver's TrajectorySource interpolates it at 100 Hz, slew-limits and
  clamps the goals, and holds the last point. A trajectory the driver refuses ends the run with
  its reasons.
- Every 10 ms step: the centre of pressure from the floor contacts' normal forces (a step with no
  normal force at all has none: counted as no_pressure_steps, not in the fraction), inside the
  (closed) support polygon of the actual contacts, which must span an area; the lift of the base's frames
  above the floor; the servos' torques against their limit. The actual contacts are MuJoCo's floor
  contacts plus the frames whose capsule is within CONTACT_GAP_M of the floor: a body lying flat is
  statically indeterminate, and MuJoCo's solver may carry its weight on two capsules for a step
  while the others touch with no force (the polygon would collapse to a line though nothing
  tips) or on one capsule (the CoP then sits on a vertex of the polygon: on it, not outside).
  Tipping about an edge lifts the frames beyond it by more than CONTACT_GAP_M within a degree,
  leaving a polygon of no area: counted outside.
- The base, as planned at each moment (the stage the trajectory is in: frames from its active-module
  count on; before the first stage the first's, after the last the last's): the CoM's signed
  distance to the polygon of the base's actual contacts (its floor contacts pushing up plus its
  frames within BASE_GAP_M of the floor; no area: outside), as the planner keeps the ZMP inside
  U of the base. BASE_GAP_M is wider than CONTACT_GAP_M: the servos give, and a base module may
  rise a few millimetres while the modules just made active still rest on the floor (COBRA's
  base frames 6-8 rise 3.5 mm as its last raise starts); tipping lifts the base far more.
  While the last posture is held: the floor's normal force on the modules the plan rests on (the
  base, and an active module planned within REST_GAP_M of the floor) and on the others, against
  the robot's weight; a tipped robot rests part of it on modules planned in the air.
- tipped: a frame of the planned base rose more than LIFT_TIPPED_M off the floor (a base module
  lifting off unplanned), or the CoP left the contacts' polygon (or the floor carried nothing), or
  the CoM left the base's contact polygon, for more than TIPPED_AFTER_S in a row; or the
  floor carried more than AIR_LOAD_MAX of the weight on modules planned in the air, on average while
  the last posture was held (what the base does not carry then is on those, or on the pipe's wall
  when the head leans on it: the wall is no tipping).
- Self-collision is on in the plant (physics.self_collision, whatever sim.yaml says): links that
  are not neighbours collide. Steps with a contact between two links are counted
  (run.json's self_contact_steps); the planner keeps the modules apart, so this should be 0.
- outcome (verdict()): "tipped" as above; else "missed_pipe" when a pipe was given and the head
  did not end inside its bore: farther from its axis than the pipe's radius less a module's radius
  (the bore the planner aims the head into), or not above the mouth; else "missed_height" when the
  head ended more than HEIGHT_TOL_M below the height the plan reached; else "ok". run.json's
  `reason` says why in one line ("" when ok).
"""
import dataclasses
import math
from typing import Callable, NamedTuple, Optional

import mujoco
import numpy as np

from snake_autonomy import _core
from snake_autonomy.missions.scout import RESULT_MARGIN_S
from snake_autonomy.paths import config_path
from snake_autonomy.planning.fbsr.pipe_scene import pipe_mjcf
from snake_autonomy.planning.fbsr.plan_io import stage_samples
from snake_autonomy.planning.fbsr.planner import Plan
from snake_autonomy.planning.fbsr.support import Support
from snake_autonomy.planning.fbsr.trajectory import MIN_LEAD_IN_S, plan_points
from snake_autonomy.runs.batch import LockStepDriver, load_driver_config
from snake_autonomy.runs.scout_executor import DriverTrajectoryExecutor
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.plant import Plant

DRIVER_PERIOD_S = 0.01
SETTLE_S = 1.0
HOLD_S = 1.5
COP_TOLERANCE_M = 1e-6
LIFT_TIPPED_M = 0.02
MIN_NORMAL_FORCE_N = 0.05
CONTACT_GAP_M = 0.001
BASE_GAP_M = 0.005
TIPPED_AFTER_S = 0.1
AIR_LOAD_MAX = 0.1          # share of the weight the floor carries on modules planned in the air, held
REST_GAP_M = 0.005          # a module this close to the floor in the plan may rest on it
HEIGHT_TOL_M = 0.03         # the head may end this much below the planned height (servo sag: 2-6 mm)


class Verdict(NamedTuple):
    tipped: bool
    outcome: str        # "ok", "tipped", "missed_pipe" or "missed_height"
    reason: str         # one line; "" when ok


@dataclasses.dataclass
class Measured:
    """What the monitor measured over a run, as verdict() reads it."""
    max_lift_m: float = 0.0                 # highest frame of the final base above lying
    longest_outside_s: float = 0.0          # CoP outside the contacts' polygon, longest spell
    longest_no_pressure_s: float = 0.0      # no floor pressure at all, longest spell
    longest_com_outside_s: float = 0.0      # CoM outside the base's contact polygon, longest spell
    base_load_fraction: float = 1.0         # floor force on the resting modules / weight, mean over the hold
    air_load_fraction: float = 0.0          # floor force on the modules planned in the air / weight, same
    head_z_m: Optional[float] = None        # the head's final height ...
    target_z_m: Optional[float] = None      # ... and the plan's (None: not checked)
    head_to_axis_m: Optional[float] = None  # with a pipe: the head's final distance to its axis,
    bore_limit_m: Optional[float] = None    # the bore's limit on it,
    mouth_m: Optional[float] = None         # and the mouth's height


def verdict(measured: Measured) -> Verdict:
    """How a run ended, from what the monitor measured: tipped when the planned base lifted more than
    LIFT_TIPPED_M, the support was lost (CoP outside the contacts, no floor pressure, or the CoM
    outside the base's contacts) for more than TIPPED_AFTER_S, or the base carried less than
    AIR_LOAD_MAX of the weight on modules planned in the air; missed_pipe when a pipe was given
    (head_to_axis_m not None) and the head is not within bore_limit_m of its axis above the mouth;
    missed_height when the head ended more than HEIGHT_TOL_M below target_z_m. Tipping wins when
    several happened; the reason names each."""
    m = measured
    why = []
    if m.max_lift_m > LIFT_TIPPED_M:
        why.append(f"a base module lifted {1000 * m.max_lift_m:.0f} mm off the floor "
                   f"(limit {1000 * LIFT_TIPPED_M:.0f} mm)")
    if m.longest_outside_s > TIPPED_AFTER_S:
        why.append(f"the centre of pressure left the contacts' polygon for {m.longest_outside_s:.2f} s "
                   f"(limit {TIPPED_AFTER_S} s)")
    if m.longest_no_pressure_s > TIPPED_AFTER_S:
        why.append(f"the floor carried no weight for {m.longest_no_pressure_s:.2f} s (limit {TIPPED_AFTER_S} s)")
    if m.longest_com_outside_s > TIPPED_AFTER_S:
        why.append(f"the centre of mass left the polygon of the base's contacts for {m.longest_com_outside_s:.2f} s "
                   f"(limit {TIPPED_AFTER_S} s)")
    if not m.air_load_fraction <= AIR_LOAD_MAX:
        why.append(f"the floor carried {100 * m.air_load_fraction:.0f} % of the weight on modules planned in the air "
                   f"(at most {100 * AIR_LOAD_MAX:.0f} %; the base {100 * m.base_load_fraction:.0f} %)")
    reasons = ["the robot tipped: " + ", ".join(why)] if why else []
    missed_pipe = False
    if m.head_to_axis_m is not None:
        if not m.head_to_axis_m <= m.bore_limit_m:
            missed_pipe = True
            reasons.append(f"missed the pipe: the head ended {m.head_to_axis_m:.3f} m from the pipe's axis, outside "
                           f"the bore ({m.bore_limit_m:.3f} m: the pipe's radius less a module's radius)")
        elif m.mouth_m is not None and not m.head_z_m > m.mouth_m:
            missed_pipe = True
            reasons.append(f"missed the pipe: the head ended at {m.head_z_m:.3f} m, below the mouth "
                           f"({m.mouth_m:.3f} m)")
    missed_height = m.target_z_m is not None and not m.head_z_m >= m.target_z_m - HEIGHT_TOL_M
    if missed_height:
        reasons.append(f"missed the height: the head ended at {m.head_z_m:.3f} m, more than "
                       f"{1000 * HEIGHT_TOL_M:.0f} mm below the plan's {m.target_z_m:.3f} m")
    outcome = "tipped" if why else "missed_pipe" if missed_pipe else "missed_height" if missed_height else "ok"
    return Verdict(bool(why), outcome, "; ".join(reasons))


def send_through_driver(plant: Plant, plan: Plan, sample_period_s: float,
                        on_step: Callable[[float], None], period_s: float = DRIVER_PERIOD_S,
                        result_margin_s: float = RESULT_MARGIN_S) -> None:
    """The plan executed by the driver's trajectory execution on `plant`; on_step(t) after each
    10 ms step until the driver reports the trajectory done. ValueError with the driver's reasons
    when it refuses or aborts the trajectory. TimeoutError when the driver has not reported its end
    within the trajectory's duration (the last point's time_from_start) + result_margin_s of plant
    time from handing it over (a stuck or dead driver), as the mission node bounds its wait for a
    final status (nodes/scout_trajectory.py, ~scout_result_margin_s)."""
    if not (isinstance(result_margin_s, (int, float)) and math.isfinite(result_margin_s) and result_margin_s > 0):
        raise ValueError(f"result_margin_s: must be a positive number of seconds, got {result_margin_s!r}")
    robot = plant.robot
    driver = LockStepDriver(robot, _core.GaitLibrary.from_yaml(str(config_path("gaits.yaml"))), plant,
                            load_driver_config(config_path("driver.yaml")))
    executor = DriverTrajectoryExecutor(driver.controller, result_margin_s)
    trajectory = plan_points(plan, sample_period_s)
    duration_s = trajectory.duration_s
    t0 = plant.time_s
    why = executor.execute(trajectory, t0)
    if why:
        raise ValueError(f"the driver refused the plan's trajectory: {why}")
    t = 0.0
    while True:
        driver.update(t0 + t, period_s)
        plant.step_to(t0 + t + period_s)
        on_step(t)
        t += period_s
        if executor.finished(t0 + t):          # done, aborted, or given up after duration + margin
            break
    if executor.gave_up:
        raise TimeoutError(f"the driver reported no end of the plan's trajectory within "
                           f"{duration_s + result_margin_s:.1f} s of handing it over ({duration_s:.1f} s "
                           f"trajectory + {result_margin_s:.1f} s, plant time)")
    if executor.aborted:
        raise ValueError(f"the driver aborted the plan's trajectory: {executor.aborted}")


def floor_contacts(model, data, floor_geom: int):
    """((k, 2) points xy, (k,) normal forces N, (k,) modules) of the floor contacts pushing up. Module j
    (frames j, j + 1) is the j-th body from base_link (the head) on, as mjcf.py nests them."""
    head = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base_link")
    points, forces, modules = [], [], []
    f6 = np.zeros(6)
    for i in range(data.ncon):
        c = data.contact[i]
        if floor_geom not in (c.geom1, c.geom2):
            continue
        mujoco.mj_contactForce(model, data, i, f6)
        fz = abs(float((c.frame.reshape(3, 3).T @ f6[:3])[2]))
        if fz > MIN_NORMAL_FORCE_N:
            points.append(c.pos[:2].copy())
            forces.append(fz)
            modules.append(int(model.geom_bodyid[c.geom2 if c.geom1 == floor_geom else c.geom1]) - head)
    return np.array(points).reshape(-1, 2), np.array(forces), np.array(modules, int)


def centre_of_pressure(model, data, floor_geom: int):
    """(CoP xy or None, (k, 2) contact points xy) of the floor contacts pushing up."""
    p, f, _ = floor_contacts(model, data, floor_geom)
    if not len(f):
        return None, p
    return (f[:, None] * p).sum(axis=0) / f.sum(), p


def self_contacts(model, data) -> int:
    """Contacts between two geoms of the robot (both on bodies of base_link's tree: the pipe's wall
    is a body of the world's too, not of the robot)."""
    robot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base_link")
    root = model.body_rootid[model.geom_bodyid]
    return sum(1 for i in range(data.ncon)
               if root[data.contact[i].geom1] == robot and root[data.contact[i].geom2] == robot)


def longest_run(flags) -> int:
    """The longest run of True in flags."""
    longest = run = 0
    for flag in flags:
        run = run + 1 if flag else 0
        longest = max(longest, run)
    return longest


class Monitor:
    """What one run measures at every driver step. `schedule`: (time from the trajectory's start,
    first base module) of each stage, in order; a call with no time is the held last posture."""

    def __init__(self, plant: Plant, torque_limit_nm: float, schedule=((0.0, 0),), resting=None):
        self.plant = plant
        self.floor = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        self.torque_limit_nm = torque_limit_nm
        self.radius_m = float(plant.robot.link_radius_m)
        self.inside, self.max_torque_ratio, self.max_lift_m = [], 0.0, 0.0
        self.max_stage_base_rise_m = 0.0   # the current stage's base frames, highest above the floor
        self.no_pressure_steps = 0    # steps with no floor contact pushing up: no CoP to check
        self.longest_no_pressure, self._no_pressure_run = 0, 0
        self.base_from = plant.robot.num_frames   # frames >= this index are the final base
        self.self_contact_steps = 0   # steps with a contact between two of the robot's links
        self.schedule = list(schedule)
        # The modules the held posture rests on as planned (the base and any active module left
        # on the floor): module indices; None: the final base's.
        self.resting = None if resting is None else np.asarray(resting, int)
        self.com_margins = []         # the CoM's signed distance to the base's contact polygon (m)
        self.hold_loads = []          # floor force on the resting modules / weight, while the last posture is held
        self.hold_air_loads = []      # ... and on the others
        base_link = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_BODY, "base_link")
        self.weight_n = float(plant.model.body_subtreemass[base_link] * -plant.model.opt.gravity[2])

    def base_at(self, t) -> int:
        """The first module of the base at trajectory time t (None: the held last posture)."""
        if t is None:
            return self.schedule[-1][1]
        return [m for t0, m in self.schedule if t0 <= t][-1] if t >= self.schedule[0][0] else self.schedule[0][1]

    def __call__(self, t=None) -> None:
        model, data = self.plant.model, self.plant.data
        points, forces, modules = floor_contacts(model, data, self.floor)
        if self_contacts(model, data):
            self.self_contact_steps += 1
        frames = self.plant.frame_positions()
        touching = frames[:, 2] - self.radius_m < CONTACT_GAP_M
        contacts = np.vstack([points, frames[touching, :2]])
        if not len(forces):
            # MuJoCo's soft contacts can carry no normal force for one 10 ms step while the body
            # lies within a millimetre of the floor (a micro-bounce as tick-quantised goals step):
            # no pressure, no centre of pressure; counted apart, tipping shows as lift instead.
            self.no_pressure_steps += 1
            self._no_pressure_run += 1
            self.longest_no_pressure = max(self.longest_no_pressure, self._no_pressure_run)
        else:
            self._no_pressure_run = 0
            cop = (forces[:, None] * points).sum(axis=0) / forces.sum()
            self.inside.append(bool(Support.of(contacts).signed_distance([cop])[0] >= -COP_TOLERANCE_M))
        first = self.base_at(t)
        on_base = modules >= first
        base = frames[first:]
        if len(base):
            self.max_stage_base_rise_m = max(self.max_stage_base_rise_m, float((base[:, 2] - self.radius_m).max()))
        base_contacts = np.vstack([points[on_base], base[base[:, 2] - self.radius_m < BASE_GAP_M, :2]])
        com = self.plant.center_of_mass()[:2]
        self.com_margins.append(float(Support.of(base_contacts).signed_distance([com])[0]))
        if t is None:
            rests = on_base if self.resting is None else np.isin(modules, self.resting)
            self.hold_loads.append(float(forces[rests].sum()) / self.weight_n)
            self.hold_air_loads.append(float(forces[~rests].sum()) / self.weight_n)
        ratio = np.abs(self.plant.actuator_torques_nm()).max() / self.torque_limit_nm
        self.max_torque_ratio = max(self.max_torque_ratio, float(ratio))
        z = frames[self.base_from:, 2]
        if len(z):
            self.max_lift_m = max(self.max_lift_m, float((z - self.radius_m).max()))

    def longest_outside_s(self) -> float:
        return longest_run(not ok for ok in self.inside) * DRIVER_PERIOD_S

    def measured(self) -> Measured:
        return Measured(
            max_lift_m=self.max_lift_m, longest_outside_s=self.longest_outside_s(),
            longest_no_pressure_s=self.longest_no_pressure * DRIVER_PERIOD_S,
            longest_com_outside_s=longest_run(d < -COP_TOLERANCE_M for d in self.com_margins) * DRIVER_PERIOD_S,
            base_load_fraction=float(np.mean(self.hold_loads)) if self.hold_loads else 1.0,
            air_load_fraction=float(np.mean(self.hold_air_loads)) if self.hold_air_loads else 0.0)


def resting_modules(chain, q, active_modules: int) -> np.ndarray:
    """The modules that posture q rests on as planned: the base (modules from active_modules on) and
    every active module with a frame within REST_GAP_M of the floor (module j spans frames j, j + 1)."""
    z = chain.pose(q).positions[:, 2] - chain.radius_m
    low = np.minimum(z[:-1], z[1:]) < REST_GAP_M
    low[active_modules:] = True
    return np.flatnonzero(low)


def run_plan(plan: Plan, sim_yaml, seed: int = 0, pipe=None,
             sample_period_s: float = 0.05, record: Optional[list] = None) -> dict:
    """Execute `plan` in a fresh plant (sim.yaml's physics, seed's draws); metrics.json's dict."""
    chain = plan.chain
    robot = chain.robot
    sim = SimConfig.from_yaml(sim_yaml)
    sim = dataclasses.replace(sim, physics=dataclasses.replace(sim.physics, self_collision=True))
    params = sim.draw(seed, num_joints=robot.num_joints)
    samples = stage_samples(plan, sample_period_s)
    q = np.array([qq for _, _, qq in samples])
    start_pose = chain.pose(q[0])
    heading = float(np.arctan2(start_pose.rotations[0][1, 0], start_pose.rotations[0][0, 0]))
    plant = Plant(robot, params, start=(*start_pose.positions[0, :2], heading), q0_rad=q[0],
                  scene_xml=pipe_mjcf(pipe) if pipe is not None else "")
    # The base of every stage: frames from its active-module count on, from the stage's start in
    # the driver's trajectory (plan_points: the first point at MIN_LEAD_IN_S); the final base is
    # the smallest, and the one held at the end. Lift is measured on the final base's frames.
    starts = MIN_LEAD_IN_S + np.concatenate([[0.0], np.cumsum([s.t_end_s for s in plan.stages])[:-1]])
    monitor = Monitor(plant, params.config.servo.torque_limit_nm,
                      [(float(t), s.active_modules) for t, s in zip(starts, plan.stages)],
                      resting_modules(chain, plan.q_end, plan.active_modules))
    plant.step(SETTLE_S)
    monitor.base_from = plan.active_modules
    step = (lambda t: (monitor(t), record.append((t, plant.frame_positions())))) \
        if record is not None else monitor
    send_through_driver(plant, plan, sample_period_s, step)
    for _ in range(int(round(HOLD_S / DRIVER_PERIOD_S))):
        plant.step(DRIVER_PERIOD_S)
        monitor()
    head = plant.frame_positions()[0]
    measured = dataclasses.replace(monitor.measured(), head_z_m=float(head[2]),
                                   target_z_m=float(plan.final_head_height_m))
    if pipe is not None:
        measured = dataclasses.replace(
            measured, head_to_axis_m=float(np.hypot(head[0] - pipe.x_m, head[1] - pipe.y_m)),
            bore_limit_m=float(pipe.radius_m - chain.radius_m),   # the planner's "under the mouth" rule
            mouth_m=float(pipe.mouth_m))
    v = verdict(measured)
    metrics = {
        "tipped": v.tipped,
        "outcome": v.outcome,
        "cop_inside_fraction": float(np.mean(monitor.inside)),
        "final_head_height_m": float(head[2]),
        "planned_head_height_m": float(plan.final_head_height_m),
        "max_torque_ratio": float(monitor.max_torque_ratio),
        "active_modules": int(plan.active_modules),
    }
    extra = {"head_xy_m": head[:2].tolist(), "max_base_lift_m": monitor.max_lift_m,
             "max_stage_base_rise_m": monitor.max_stage_base_rise_m,
             "no_pressure_steps": monitor.no_pressure_steps,
             "self_contact_steps": monitor.self_contact_steps,
             "base_load_fraction": measured.base_load_fraction, "air_load_fraction": measured.air_load_fraction,
             "min_com_margin_m": float(min(monitor.com_margins)) if monitor.com_margins else None,
             "longest_com_outside_s": measured.longest_com_outside_s,
             "limit_violations": int(plant.limit_violations), "reason": v.reason}
    if pipe is not None:
        extra.update(head_to_pipe_axis_m=measured.head_to_axis_m, bore_limit_m=measured.bore_limit_m,
                     head_in_bore=bool(measured.head_to_axis_m <= measured.bore_limit_m
                                       and measured.head_z_m > pipe.mouth_m))
    return {"metrics": metrics, "extra": extra}
