"""A plan run in the MuJoCo plant, checked from the contact forces: metrics.json of the contract

    {"tipped": bool, "outcome": "ok" | "tipped" | "missed_pipe", "cop_inside_fraction": float,
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
- tipped: a frame of the planned base rose more than LIFT_TIPPED_M off the floor (a base module
  lifting off unplanned), or the CoP left the contacts' polygon (or the floor carried nothing) for
  more than 0.1 s in a row.
- Self-collision is on in the plant (physics.self_collision, whatever sim.yaml says): links that
  are not neighbours collide. Steps with a contact between two links are counted
  (run.json's self_contact_steps); the planner keeps the modules apart, so this should be 0.
- outcome (verdict()): "tipped" as above; else "missed_pipe" when a pipe was given and the head
  ended farther from its axis than the pipe's radius less a module's radius (the bore the planner
  aims the head into); else "ok". run.json's `reason` says why in one line ("" when ok).
"""
import dataclasses
from typing import Callable, NamedTuple, Optional

import mujoco
import numpy as np

from snake_autonomy import _core
from snake_autonomy.paths import config_path
from snake_autonomy.planning.fbsr.pipe_scene import pipe_mjcf
from snake_autonomy.planning.fbsr.plan_io import stage_samples
from snake_autonomy.planning.fbsr.planner import Plan
from snake_autonomy.planning.fbsr.support import Support
from snake_autonomy.planning.fbsr.trajectory import plan_points
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
TIPPED_AFTER_S = 0.1


class Verdict(NamedTuple):
    tipped: bool
    outcome: str        # "ok", "tipped" or "missed_pipe"
    reason: str         # one line; "" when ok


def verdict(max_lift_m: float, longest_outside_s: float, longest_no_pressure_s: float,
            head_to_axis_m: Optional[float] = None, bore_limit_m: Optional[float] = None) -> Verdict:
    """How a run ended, from what the monitor measured: tipped when the planned base lifted more than
    LIFT_TIPPED_M or the support was lost (CoP outside the contacts, or no floor pressure) for more
    than TIPPED_AFTER_S; missed_pipe when a pipe was given (head_to_axis_m not None) and the head
    is not within bore_limit_m of its axis. Tipping wins when both happened; the reason names both."""
    why = []
    if max_lift_m > LIFT_TIPPED_M:
        why.append(f"a base module lifted {1000 * max_lift_m:.0f} mm off the floor "
                   f"(limit {1000 * LIFT_TIPPED_M:.0f} mm)")
    if longest_outside_s > TIPPED_AFTER_S:
        why.append(f"the centre of pressure left the contacts' polygon for {longest_outside_s:.2f} s "
                   f"(limit {TIPPED_AFTER_S} s)")
    if longest_no_pressure_s > TIPPED_AFTER_S:
        why.append(f"the floor carried no weight for {longest_no_pressure_s:.2f} s (limit {TIPPED_AFTER_S} s)")
    reasons = ["the robot tipped: " + ", ".join(why)] if why else []
    missed = head_to_axis_m is not None and not head_to_axis_m <= bore_limit_m
    if missed:
        reasons.append(f"missed the pipe: the head ended {head_to_axis_m:.3f} m from the pipe's axis, "
                       f"outside the bore ({bore_limit_m:.3f} m: the pipe's radius less a module's radius)")
    outcome = "tipped" if why else "missed_pipe" if missed else "ok"
    return Verdict(bool(why), outcome, "; ".join(reasons))


def send_through_driver(plant: Plant, plan: Plan, sample_period_s: float,
                        on_step: Callable[[float], None], period_s: float = DRIVER_PERIOD_S) -> None:
    """The plan executed by the driver's trajectory execution on `plant`; on_step(t) after each
    10 ms step until the driver reports the trajectory done. ValueError with the driver's reasons
    when it refuses or aborts the trajectory."""


    robot = plant.robot
    driver = LockStepDriver(robot, _core.GaitLibrary.from_yaml(str(config_path("gaits.yaml"))), plant,
                            load_driver_config(config_path("driver.yaml")))
    executor = DriverTrajectoryExecutor(driver.controller)
    t0 = plant.time_s
    why = executor.execute(plan_points(plan, sample_period_s), t0)
    if why:
        raise ValueError(f"the driver refused the plan's trajectory: {why}")
    t = 0.0
    while True:
        driver.update(t0 + t, period_s)
        plant.step_to(t0 + t + period_s)
        on_step(t)
        t += period_s
        if executor.finished(t0 + t):
            break
    if executor.aborted:
        raise ValueError(f"the driver aborted the plan's trajectory: {executor.aborted}")


def centre_of_pressure(model, data, floor_geom: int):
    """(CoP xy or None, (k, 2) contact points xy) of the floor contacts pushing up."""
    points, forces = [], []
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
    if not forces:
        return None, np.zeros((0, 2))
    p, f = np.array(points), np.array(forces)
    return (f[:, None] * p).sum(axis=0) / f.sum(), p


def self_contacts(model, data) -> int:
    """Contacts between two geoms of the robot (both on a body other than the world)."""
    body = model.geom_bodyid
    return sum(1 for i in range(data.ncon)
               if body[data.contact[i].geom1] != 0 and body[data.contact[i].geom2] != 0)


class Monitor:
    """What one run measures at every driver step."""

    def __init__(self, plant: Plant, torque_limit_nm: float):
        self.plant = plant
        self.floor = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        self.torque_limit_nm = torque_limit_nm
        self.radius_m = float(plant.robot.link_radius_m)
        self.inside, self.max_torque_ratio, self.max_lift_m = [], 0.0, 0.0
        self.no_pressure_steps = 0    # steps with no floor contact pushing up: no CoP to check
        self.longest_no_pressure, self._no_pressure_run = 0, 0
        self.base_from = plant.robot.num_frames   # frames >= this index are the planned base
        self.self_contact_steps = 0   # steps with a contact between two of the robot's links

    def __call__(self, _t=None) -> None:
        cop, contacts = centre_of_pressure(self.plant.model, self.plant.data, self.floor)
        if self_contacts(self.plant.model, self.plant.data):
            self.self_contact_steps += 1
        frames = self.plant.frame_positions()
        touching = frames[frames[:, 2] - self.radius_m < CONTACT_GAP_M, :2]
        contacts = np.vstack([contacts, touching])
        if cop is None:
            # MuJoCo's soft contacts can carry no normal force for one 10 ms step while the body
            # lies within a millimetre of the floor (a micro-bounce as tick-quantised goals step):
            # no pressure, no centre of pressure; counted apart, tipping shows as lift instead.
            self.no_pressure_steps += 1
            self._no_pressure_run += 1
            self.longest_no_pressure = max(self.longest_no_pressure, self._no_pressure_run)
        else:
            self._no_pressure_run = 0
            self.inside.append(bool(Support.of(contacts).signed_distance([cop])[0] >= -COP_TOLERANCE_M))
        ratio = np.abs(self.plant.actuator_torques_nm()).max() / self.torque_limit_nm
        self.max_torque_ratio = max(self.max_torque_ratio, float(ratio))
        z = frames[self.base_from:, 2]
        if len(z):
            self.max_lift_m = max(self.max_lift_m, float((z - self.radius_m).max()))

    def longest_outside_s(self) -> float:
        longest = run = 0
        for ok in self.inside:
            run = 0 if ok else run + 1
            longest = max(longest, run)
        return longest * DRIVER_PERIOD_S


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
    monitor = Monitor(plant, params.config.servo.torque_limit_nm)
    plant.step(SETTLE_S)
    # The base of every stage: frames from its active-module count on; the final base is the
    # smallest, and the one held at the end. Lift is measured on the final base's frames.
    monitor.base_from = plan.active_modules
    step = (lambda t: (monitor(), record.append((t, plant.frame_positions())))) \
        if record is not None else monitor
    send_through_driver(plant, plan, sample_period_s, step)
    for _ in range(int(round(HOLD_S / DRIVER_PERIOD_S))):
        plant.step(DRIVER_PERIOD_S)
        monitor()
    head = plant.frame_positions()[0]
    head_to_axis_m = bore_limit_m = None
    if pipe is not None:
        head_to_axis_m = float(np.hypot(head[0] - pipe.x_m, head[1] - pipe.y_m))
        bore_limit_m = float(pipe.radius_m - chain.radius_m)   # the planner's "under the mouth" rule
    v = verdict(monitor.max_lift_m, monitor.longest_outside_s(), monitor.longest_no_pressure * DRIVER_PERIOD_S,
                head_to_axis_m, bore_limit_m)
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
             "no_pressure_steps": monitor.no_pressure_steps,
             "self_contact_steps": monitor.self_contact_steps,
             "limit_violations": int(plant.limit_violations), "reason": v.reason}
    if pipe is not None:
        extra.update(head_to_pipe_axis_m=head_to_axis_m, bore_limit_m=bore_limit_m)
    return {"metrics": metrics, "extra": extra}
