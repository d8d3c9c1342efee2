"""The batch simulator's trajectory executor for scout stops (missions/scout.py TrajectoryExecutor).

It stands in for the driver's TrajectorySource (issue 11) until that is bound in Python: while a
trajectory is active, `apply(t_s)` after every driver update overrides the plant's joint goals with
the trajectory, interpolated as planning/fbsr/execute.py's `send_goals` does (a clamped cubic spline
through the points, from the joints' present goals at the start); after the last point it holds it
until `release()` hands the joints back to the driver (when locomotion resumes). A trajectory is
refused whole, with the reasons, when its joint names, sizes or times are wrong or a point leaves
the joint limits.
"""
from typing import Optional

import numpy as np
from scipy.interpolate import CubicSpline

from ..planning.fbsr.trajectory import driver_joint_names
from .plant import Plant

LIMIT_TOLERANCE_RAD = 1e-6


class PlantTrajectoryExecutor:
    def __init__(self, plant: Plant):
        self.plant = plant
        self.names = driver_joint_names(plant.num_joints)
        self._spline: Optional[CubicSpline] = None
        self._t0 = 0.0
        self._end_s = 0.0
        self.sent = []                      # (t_s, trajectory) accepted, in order

    def problems(self, trajectory) -> list:
        out = []
        if list(trajectory.joint_names) != self.names:
            out.append(f"joint names {list(trajectory.joint_names)[:3]}... != {self.names[:3]}...")
        if not trajectory.points:
            return out + ["no points"]
        t = np.array([p.time_from_start_s for p in trajectory.points], float)
        q = np.array([p.positions_rad for p in trajectory.points], float)
        if q.ndim != 2 or q.shape[1] != len(self.names):
            return out + [f"positions of {q.shape[-1]} joints, the robot has {len(self.names)}"]
        if t[0] <= 0 or np.any(np.diff(t) <= 0):
            out.append("time_from_start must be > 0 and strictly increasing")
        low = np.flatnonzero((q < self.plant.lower_rad - LIMIT_TOLERANCE_RAD).any(axis=0)
                             | (q > self.plant.upper_rad + LIMIT_TOLERANCE_RAD).any(axis=0))
        if low.size:
            out.append(f"{', '.join(self.names[j] for j in low)} beyond the joint limits")
        return out

    def execute(self, trajectory, t_s: float) -> str:
        why = self.problems(trajectory)
        if why:
            return "; ".join(why)
        t = np.array([0.0] + [p.time_from_start_s for p in trajectory.points], float)
        q = np.vstack([self.plant.joint_goals_rad()[None, :],
                       np.array([p.positions_rad for p in trajectory.points], float)])
        self._spline = CubicSpline(t, q, axis=0, bc_type="clamped")
        self._t0, self._end_s = float(t_s), float(t[-1])
        self.sent.append((t_s, trajectory))
        return ""

    def finished(self, t_s: float) -> bool:
        return self._spline is None or t_s - self._t0 >= self._end_s

    @property
    def active(self) -> bool:
        return self._spline is not None

    def apply(self, t_s: float) -> None:
        """Override the driver's goals with the trajectory at t_s (its last point once past it)."""
        if self._spline is not None:
            self.plant.set_joint_targets(self._spline(min(max(t_s - self._t0, 0.0), self._end_s)))

    def release(self) -> None:
        """Hand the joints back to the driver (locomotion resumes)."""
        self._spline = None
