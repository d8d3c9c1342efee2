"""The batch simulator's trajectory executor for scout stops (missions/scout.py TrajectoryExecutor).

Scout trajectories go through the driver's own trajectory execution, as on the robot: the batch
simulator's DriverController (runs/batch.py LockStepDriver, the C++ loop driver_node runs) takes them
with `command_trajectory` (driver::TrajectorySource: refused whole with every reason; cubic Hermite
from the present goals; the same slew limit and clamp as the gait's; the last point held, state
holding). The ROS side's executor publishes on driver/joint_trajectory (nodes/scout_trajectory.py).
As that one, it never waits forever: a trajectory with no final phase within its duration +
``result_margin_s`` of being handed over (a driver that stopped stepping, or never ends it) counts as
finished with `aborted` saying so.
"""
import numpy as np

from snake_autonomy.missions.scout import RESULT_MARGIN_S
from snake_autonomy.planning.fbsr.trajectory import driver_joint_names


class DriverTrajectoryExecutor:
    """Scout trajectories through the driver's own trajectory execution (DriverController.
    command_trajectory, the TrajectorySource that driver_node runs on driver/joint_trajectory): the
    same checks, cubic interpolation from the present goals, slew limit and clamp as on the robot.
    `execute` hands the trajectory over ('' or every reason it was refused); the loop takes it at its
    next update(); `finished` once the driver reports it done (holding its last point) or aborted
    (`aborted` says why). A gait command ends a trajectory in the driver: `release` only forgets it."""

    def __init__(self, controller, result_margin_s: float = RESULT_MARGIN_S):
        self.controller = controller
        self.result_margin_s = float(result_margin_s)
        self._deadline_s = 0.0
        self.names = driver_joint_names(len(controller.ids))
        self._sequence = None               # the driver's progress sequence of ours, once taken
        self._before = 0
        self.sent = []                      # (t_s, trajectory) accepted, in order
        self.aborted = ""
        self.gave_up = False                # the last trajectory's end never came (aborted says so)

    def execute(self, trajectory, t_s: float) -> str:
        if not trajectory.points:
            return "points: empty (at least one point is needed)"
        times = [p.time_from_start_s for p in trajectory.points]
        q = np.array([p.positions_rad for p in trajectory.points], float)
        given = [p for p in trajectory.points if len(getattr(p, "velocities_rad_s", ()) or ()) > 0]
        v = np.array([p.velocities_rad_s for p in trajectory.points], float) \
            if len(given) == len(trajectory.points) else None
        self._before = self.controller.trajectory_progress["sequence"]
        why = self.controller.command_trajectory(list(trajectory.joint_names), times, q, v,
                                                 id=f"scout {len(self.sent) + 1}")
        if why:
            return why
        self._sequence, self.aborted, self.gave_up = self._before + 1, "", False
        self._deadline_s = t_s + times[-1] + self.result_margin_s
        self.sent.append((t_s, trajectory))
        return ""

    def finished(self, t_s: float) -> bool:
        if self._sequence is None:
            return True
        p = self.controller.trajectory_progress
        waiting = p["sequence"] < self._sequence or (p["sequence"] == self._sequence and p["phase"] == "running")
        if waiting and t_s > self._deadline_s:
            self.gave_up = True
            self.aborted = (f"no final phase for trajectory 'scout {len(self.sent)}' within "
                            f"{self._deadline_s - self.sent[-1][0]:.1f} s of handing it over "
                            f"(the driver is at phase '{p['phase']}' of sequence {p['sequence']})")
            return True
        if waiting:
            return False                    # not taken yet, or running
        if p["phase"] == "aborted":
            self.aborted = f"{p['abort']}: {p['reason']}"
        return True

    def head_height_m(self) -> float:
        """NaN: the batch run measures the plant's head itself, every physics step (runs/batch.py)."""
        return float("nan")

    @property
    def active(self) -> bool:
        return self._sequence is not None

    def release(self) -> None:
        self._sequence = None
