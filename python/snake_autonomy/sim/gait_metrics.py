"""Open-loop locomotion figures of the plant: speed, sideways speed, turn rate.

Heading is the principal axis of the link positions in the ground plane (the virtual chassis of
Rollinson & Choset), pointing from tail to head, sampled once per gait cycle at the
same phase so the body's oscillation cancels; speeds come from the centre of mass over whole
cycles after settling cycles (from a straight body, the first two cycles of sidewinding are up to
60 % faster than the steady state).
"""
from dataclasses import dataclass

import numpy as np


def body_heading_rad(frame_positions: np.ndarray) -> float:
    """Heading (rad) of the body's principal axis in the xy plane, oriented tail -> head."""
    xy = frame_positions[:, :2]
    centred = xy - xy.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    axis = vt[0]
    if np.dot(xy[0] - xy[-1], axis) < 0:
        axis = -axis
    return float(np.arctan2(axis[1], axis[0]))


@dataclass
class GaitFigures:
    duration_s: float
    speed_m_s: float           # centre of mass, over whole cycles
    sideways_m_s: float        # component perpendicular to the mean heading (+ = to the left)
    forward_m_s: float         # component along the mean heading
    turn_rate_deg_s: float     # + = counter-clockwise seen from above
    max_torque_nm: float


def run_open_loop(plant, pattern, cycles: int = 4, settle_cycles: int = 3,
                  control_period_s: float = 0.01) -> GaitFigures:
    """Drive `plant` with pattern.joint_angles(robot, t) at the driver's rate; measure.

    pattern: a Serpenoid or a CpgGait (anything with frequency_hz and joint_angles(robot, t))."""
    robot = plant.robot
    period = 1.0 / pattern.frequency_hz
    t0 = plant.time_s
    samples = []        # (t, com, heading) once per cycle
    max_torque = 0.0
    n_steps = int(round((settle_cycles + cycles) * period / control_period_s))
    per_cycle = period / control_period_s
    next_sample = settle_cycles
    for k in range(1, n_steps + 1):
        t = t0 + k * control_period_s
        plant.set_joint_targets(pattern.joint_angles(robot, t - t0))
        plant.step_to(t)
        max_torque = max(max_torque, float(np.abs(plant.actuator_torques_nm()).max()))
        if k >= next_sample * per_cycle - 1e-9:
            samples.append((plant.time_s, plant.center_of_mass(),
                            body_heading_rad(plant.frame_positions())))
            next_sample += 1
    times = np.array([s[0] for s in samples])
    com = np.array([s[1] for s in samples])
    headings = np.unwrap([s[2] for s in samples])
    duration = times[-1] - times[0]
    disp = com[-1, :2] - com[0, :2]
    mean_heading = float(np.mean(headings))
    fwd = np.array([np.cos(mean_heading), np.sin(mean_heading)])
    left = np.array([-fwd[1], fwd[0]])
    return GaitFigures(
        duration_s=duration,
        speed_m_s=float(np.linalg.norm(disp) / duration),
        sideways_m_s=float(disp @ left / duration),
        forward_m_s=float(disp @ fwd / duration),
        turn_rate_deg_s=float(np.degrees(headings[-1] - headings[0]) / duration),
        max_torque_nm=max_torque)
