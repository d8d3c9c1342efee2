"""A plan as the driver's joint trajectory, ROS-free: the points of a trajectory_msgs/JointTrajectory.

The driver's contract (driver/joint_trajectory, the driver's TrajectorySource): joint names joint_1 ..
joint_N, positions in radians, time_from_start strictly increasing; the driver interpolates cubically
between the points, refuses a trajectory whole (with its reasons) and holds the last point. It also
slew-limits every goal to config/driver.yaml max_joint_velocity_rad_s, so a trajectory that asks for
more would be followed late: `velocity_problems` refuses it here first.

Points: the plan's stages on their sample grid (at most `period_s` apart, the stages' cubics of eq.
3-8 with their analytic velocities), offset by a lead-in. The lead-in is the time the driver gets to
move from wherever the joints are to the plan's first posture (the lying posture of the planner);
`lead_in_s` computes it from that start so the cubic the driver interpolates over it stays under the
velocity limit. `nodes/scout_trajectory.py` turns the points into the ROS message.
"""
from dataclasses import dataclass
from typing import List, Optional, Sequence

import numpy as np

from snake_autonomy.paths import config_path
from snake_autonomy.safe_yaml import load_yaml_file

from . import spline
from .planner import Plan
from .stage import sample_times

#: A cubic from rest to rest over T covering d peaks at 1.5 d / T: the interpolation bound used.
CUBIC_PEAK_FACTOR = 1.5
MIN_LEAD_IN_S = 1.0
#: The fraction of the driver's velocity limit a trajectory may use (the driver's slew limit then
#: never bites: the servo follows the planned cubic, not a clipped one).
VELOCITY_MARGIN = 0.9


@dataclass(frozen=True)
class TrajectoryPoint:
    time_from_start_s: float
    positions_rad: tuple
    velocities_rad_s: tuple


@dataclass
class JointTrajectoryPoints:
    """What a trajectory_msgs/JointTrajectory carries, without ROS."""
    joint_names: List[str]
    points: List[TrajectoryPoint]

    @property
    def duration_s(self) -> float:
        return self.points[-1].time_from_start_s if self.points else 0.0

    @property
    def final_positions_rad(self) -> np.ndarray:
        return np.asarray(self.points[-1].positions_rad, float)

    def to_dict(self) -> dict:
        return {"joint_names": list(self.joint_names),
                "points": [{"time_from_start_s": p.time_from_start_s,
                            "positions_rad": list(p.positions_rad),
                            "velocities_rad_s": list(p.velocities_rad_s)} for p in self.points]}


def driver_joint_names(num_joints: int) -> List[str]:
    """The names the driver takes: joint_1 .. joint_N."""
    return [f"joint_{i + 1}" for i in range(int(num_joints))]


def lead_in_s(q_from, q_to, max_velocity_rad_s: float, minimum_s: float = MIN_LEAD_IN_S) -> float:
    """Time for the driver's cubic from q_from to q_to at rest to stay within the velocity limit."""
    d = float(np.max(np.abs(np.asarray(q_to, float) - np.asarray(q_from, float)), initial=0.0))
    return max(float(minimum_s), CUBIC_PEAK_FACTOR * d / (VELOCITY_MARGIN * max_velocity_rad_s))


def plan_points(plan: Plan, period_s: float = 0.05, lead_in: float = MIN_LEAD_IN_S) -> JointTrajectoryPoints:
    """The plan's samples as trajectory points: the first (the plan's start posture, at rest) at
    `lead_in` seconds, then every stage's grid (the previous stage's last sample not repeated)."""
    if not lead_in > 0:
        raise ValueError(f"lead_in: must be > 0 s (the driver needs time to reach the first point), got {lead_in}")
    if not 0 < period_s <= 0.05:
        raise ValueError(f"period_s: must be in (0, 0.05] s, got {period_s}")
    n = plan.chain.num_joints
    points: List[TrajectoryPoint] = []
    t0 = float(lead_in)
    for k, stage in enumerate(plan.stages):
        times = sample_times(stage.t_end_s, period_s)
        q = stage.joints(times)
        v = np.zeros_like(q)
        m = stage.active_modules
        v[:, :m] = spline.velocities(stage.delta, stage.t_end_s, times)
        for i, t in enumerate(times):
            if k > 0 and i == 0:
                continue
            points.append(TrajectoryPoint(round(t0 + float(t), 9), tuple(float(x) for x in q[i]),
                                          tuple(float(x) for x in v[i])))
        t0 += stage.t_end_s
    return JointTrajectoryPoints(driver_joint_names(n), points)


def velocity_problems(traj: JointTrajectoryPoints, max_velocity_rad_s: float,
                      q_from: Optional[Sequence[float]] = None) -> List[str]:
    """Why the driver would not follow `traj` as planned (empty when it would): times not
    increasing, a listed velocity over the limit, or a segment whose rest-to-rest cubic would be
    (1.5 |dq| / dt); with q_from, the lead-in segment from there too."""
    out = []
    if not traj.points:
        return ["no points"]
    limit = VELOCITY_MARGIN * float(max_velocity_rad_s)
    t = np.array([p.time_from_start_s for p in traj.points], float)
    q = np.array([p.positions_rad for p in traj.points], float)
    v = np.array([p.velocities_rad_s for p in traj.points], float)
    if q.shape[1] != len(traj.joint_names):
        out.append(f"{q.shape[1]} positions per point for {len(traj.joint_names)} joint names")
    if t[0] <= 0 or np.any(np.diff(t) <= 0):
        out.append("time_from_start must be > 0 and strictly increasing")
        return out
    if q_from is not None:
        t = np.concatenate([[0.0], t])
        q = np.vstack([np.asarray(q_from, float)[None, :], q])
    listed = np.abs(v).max(initial=0.0)
    if listed > limit:
        out.append(f"a point's velocity is {listed:.2f} rad/s, over {limit:.2f} "
                   f"({VELOCITY_MARGIN:g} x max_joint_velocity_rad_s {max_velocity_rad_s:g})")
    seg = CUBIC_PEAK_FACTOR * np.abs(np.diff(q, axis=0)) / np.diff(t)[:, None]
    if seg.size and seg.max() > limit:
        i, j = np.unravel_index(np.argmax(seg), seg.shape)
        out.append(f"{traj.joint_names[j]} between t = {t[i]:.3f} and {t[i + 1]:.3f} s needs "
                   f"{seg.max():.2f} rad/s, over {limit:.2f}")
    return out


def driver_velocity_limit(path=None) -> float:
    """config/driver.yaml max_joint_velocity_rad_s (the driver's slew limit)."""

    path = path or config_path("driver.yaml")
    raw = load_yaml_file(path) or {}
    value = raw.get("max_joint_velocity_rad_s") if isinstance(raw, dict) else None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise ValueError(f"{path}: max_joint_velocity_rad_s: expected a positive number, got {value!r}")
    return float(value)
