"""One turn of the rectilinear gait on open floor, and how far the body strays from the head's track
(bench/nav_follow_the_leader prints it, test_nav_follow_the_leader checks it). reshape_step:
where each frame of the body goes when the curvature steps (test_nav_body_model checks it).

The run: straight for start_s, kappa for turn_s, straight for 60 s; the plant with nav runs' flat
belly (the robot's nav config plant:), the gait through the C++ driver (its gaits.forward, e.g.
config/gaits.yaml rectilinear) or the Python reference (its gait:, planning/rectilinear/gait.py).
Steering laws (nav.yaml gaits.steering): uniform (every yaw joint at kappa: the driver's curvature law)
or follow_the_leader (planning/rectilinear/follow_the_leader.py: the driver gets per-joint biases).
"""
import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np
from shapely.geometry import LineString, Point

from snake_autonomy import _core
from snake_autonomy.paths import config_path, robot_yaml
from snake_autonomy.planning.rectilinear.config import STEERING_LAWS as STEERING
from snake_autonomy.planning.rectilinear.config import NavConfig, nav_config_path
from snake_autonomy.planning.rectilinear.follow_the_leader import FollowTheLeader
from snake_autonomy.planning.rectilinear.planner import ground_frame
from snake_autonomy.runs.gait_driver import PlantGaitDriver
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.scales import ScaledPlant


@dataclass
class TurnSweep:
    steering: str
    heading_change_deg: float            # the head's, from the turn's start to the run's end
    head_sideways_m: Tuple[float, float]  # the head's sideways move 10 s and 20 s into the turn
    off_track_m: float                   # the farthest any frame of the body gets from the track (the
                                         # head's path so far and the straight line behind the start)


def _open_floor(robot_name: str, seed: int):
    """(robot model, its nav config, a plant on open floor with nav runs' flat belly) at the origin."""
    robot = _core.RobotModel.from_yaml(str(robot_yaml(robot_name)))
    nav = NavConfig.from_yaml(nav_config_path(robot_name))       # the robot's gaits and plant options
    sim = SimConfig.from_yaml(str(config_path("sim.yaml"))).with_flat_belly(nav.plant.flat_belly_fraction)
    return robot, nav, ScaledPlant(robot, sim.draw(seed=seed, num_joints=robot.num_joints), (0.0, 0.0, 0.0))


def turn_sweep(steering: str, kappa_per_m: float = 1.5, turn_s: float = 90.0, robot_name: str = "cobra",
               seed: int = 0, gait_source: str = "driver", start_s: float = 30.0,
               kappa_slew_per_m_s: float = 1.0) -> TurnSweep:
    if steering not in STEERING:
        raise ValueError(f"steering: expected one of {', '.join(STEERING)}, got {steering!r}")
    if gait_source not in ("driver", "reference"):
        raise ValueError(f"gait_source: expected driver or reference, got {gait_source!r}")
    robot, nav, plant = _open_floor(robot_name, seed)
    ftl = FollowTheLeader.of_robot(robot) if steering == "follow_the_leader" else None
    drive = None
    if gait_source == "driver":
        drive = PlantGaitDriver(robot, plant)
    t, dt, t_end, ramp_s = 0.0, 0.01, start_s + turn_s + 60.0, 2.0
    kappa, head, bodies = 0.0, [], []
    while t < t_end:
        pose = ground_frame(plant.frame_transform("base_link"))
        goal = kappa_per_m if start_s <= t < start_s + turn_s else 0.0
        kappa += max(-kappa_slew_per_m_s * dt, min(kappa_slew_per_m_s * dt, goal - kappa))
        if ftl is not None and t >= ramp_s:
            ftl.crawl(pose, kappa)
        if drive is not None:
            if ftl is None:
                if drive.kappa_per_m != kappa:
                    drive.command(nav.gaits.forward, kappa_per_m=kappa)
            elif round(t / dt) % 50 == 0:                        # every 0.5 s, as nav runs
                drive.command(nav.gaits.forward, bias_rad=ftl.biases())
            drive.step(t, dt)
        else:
            q = nav.gait.joint_angles(robot, max(0.0, t - ramp_s), kappa,
                                      None if ftl is None else ftl.joint_kappas())
            plant.set_joint_targets(q if t >= ramp_s else q * (t / ramp_s))
        t += dt
        plant.step_to(t)
        if round(t / dt) % 10 == 0:                              # 10 Hz
            head.append((t, *ground_frame(plant.frame_transform("base_link"))))
            bodies.append(plant.frame_positions()[1:, :2].copy())
    head = np.array(head)
    worst = 0.0
    for k in range(0, len(bodies), 20):                          # every 2 s
        track = LineString(np.vstack([[[-2.0, 0.0]], head[:k + 1, 1:3]]))
        worst = max(worst, max(track.distance(Point(p)) for p in bodies[k]))
    i0 = int(np.searchsorted(head[:, 0], start_s - 1e-6))
    c, s = math.cos(head[i0, 3]), math.sin(head[i0, 3])
    side = [-s * (head[i0 + n, 1] - head[i0, 1]) + c * (head[i0 + n, 2] - head[i0, 2]) for n in (100, 200)]
    return TurnSweep(steering, math.degrees(head[-1, 3] - head[i0, 3]), (side[0], side[1]), worst)


@dataclass
class ReshapeStep:
    kappa_per_m: float
    lateral_m: np.ndarray        # each kinematic frame's sideways move (head first; + = left, the body's
                                 # frame before the step)
    centroid_m: float            # the frames' centroid's sideways move


def reshape_step(kappa_per_m: float, robot_name: str = "cobra", seed: int = 0, settle_s: float = 20.0,
                 kappa_slew_per_m_s: float = 1.0) -> ReshapeStep:
    """Uniform curvature through the C++ driver on open floor: straight for settle_s, then kappa_per_m
    (slewed as nav runs); the frames' sideways moves from the step to 2.5 s after kappa is reached (the
    crawl in that time is along the body, mostly forward)."""
    robot, nav, plant = _open_floor(robot_name, seed)
    drive = PlantGaitDriver(robot, plant)
    t, dt, kappa = 0.0, 0.01, 0.0
    t_end = settle_s + abs(kappa_per_m) / kappa_slew_per_m_s + 2.5
    before = None
    while t < t_end:
        if before is None and t >= settle_s:
            before = plant.frame_positions()[:, :2].copy(), ground_frame(plant.frame_transform("base_link"))[2]
        goal = kappa_per_m if t >= settle_s else 0.0
        kappa += max(-kappa_slew_per_m_s * dt, min(kappa_slew_per_m_s * dt, goal - kappa))
        if drive.kappa_per_m != kappa:
            drive.command(nav.gaits.forward, kappa_per_m=kappa)
        drive.step(t, dt)
        t += dt
        plant.step_to(t)
    (a, th), b = before, plant.frame_positions()[:, :2]
    n = np.array([-math.sin(th), math.cos(th)])
    return ReshapeStep(kappa_per_m, (b - a) @ n, float((b.mean(axis=0) - a.mean(axis=0)) @ n))


@dataclass
class StopShift:
    kappa_per_m: float
    run_s: float                 # how long the gait ran before the stop
    shift_m: float               # base_link's move from the stop command to settle_s after it


def stop_shift(kappa_per_m: float, run_s: float, robot_name: str = "cobra", seed: int = 0,
               settle_s: float = 10.0) -> StopShift:
    """How far base_link moves when the navigation loop stops: the nav config's forward gait with
    curve + kappa_per_m through the C++ driver on open floor for run_s, then its stop gait (gaits.stop,
    the wave decays, kappa kept) for settle_s. What the loop's goal margin (follower.goal_margin_m)
    must cover for the robot to come to rest inside a goal's disc it stopped in."""
    robot, nav, plant = _open_floor(robot_name, seed)
    drive = PlantGaitDriver(robot, plant)
    drive.command(nav.gaits.forward, kappa_per_m=kappa_per_m)
    t, dt, step, start = 0.0, 0.01, 0, None
    while t < run_s + settle_s:
        if start is None and t >= run_s:
            start = plant.frame_transform("base_link")[:2, 3].copy()
            drive.command(nav.gaits.stop, kappa_per_m=kappa_per_m)
        drive.step(t, dt)
        step += 1
        t = step * dt
        plant.step_to(t)
    end = plant.frame_transform("base_link")[:2, 3]
    return StopShift(kappa_per_m, run_s, float(np.hypot(*(end - start))))
