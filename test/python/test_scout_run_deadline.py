"""The physics run's send_through_driver (runs/scout_execute.py) never waits forever for the driver: a
driver that takes the trajectory but never reports its end fails with a TimeoutError naming the wait
(the trajectory's duration + the margin) once that much plant time has passed. No plant, no planner:
a fake plant, a fake driver and a two-point trajectory."""
import math

import pytest

from snake_autonomy.planning.fbsr.trajectory import JointTrajectoryPoints, TrajectoryPoint
from snake_autonomy.runs import scout_execute

PERIOD_S = 0.01


class SilentController:
    """Accepts every trajectory and never takes it: its progress stays where it was."""
    ids = (1, 2)

    def __init__(self):
        self.trajectory_progress = {"sequence": 0, "phase": "idle", "abort": "", "reason": ""}
        self.commanded = []

    def command_trajectory(self, names, times, q, v, id=""):
        self.commanded.append(id)
        return ""


class DeadDriver:
    def __init__(self, robot, library, plant, config):
        self.controller = SilentController()
        self.updates = 0

    def update(self, t_s, dt_s):
        self.updates += 1


class FakePlant:
    robot = None

    def __init__(self):
        self.time_s = 2.0

    def step_to(self, t_s):
        self.time_s = t_s


@pytest.fixture
def dead_driver(monkeypatch):
    """send_through_driver with DeadDriver in place of the lock-step driver and a 1.5 s trajectory."""
    monkeypatch.setattr(scout_execute, "LockStepDriver", DeadDriver)
    points = [TrajectoryPoint(t, (0.0, 0.0), (0.0, 0.0)) for t in (0.5, 1.5)]
    monkeypatch.setattr(scout_execute, "plan_points",
                        lambda plan, period_s: JointTrajectoryPoints(["joint_1", "joint_2"], points))


def test_a_driver_that_never_reports_the_end_times_out_after_the_duration_and_the_margin(dead_driver):
    plant, steps = FakePlant(), []
    with pytest.raises(TimeoutError, match=r"no end of the plan's trajectory within 3\.5 s of handing it over "
                                           r"\(1\.5 s trajectory \+ 2\.0 s, plant time\)"):
        scout_execute.send_through_driver(plant, None, 0.05, steps.append, PERIOD_S, result_margin_s=2.0)
    # stepped through the whole wait, and no further than one step beyond it
    assert 3.5 - PERIOD_S <= steps[-1] <= 3.5 + PERIOD_S
    assert plant.time_s == pytest.approx(2.0 + 3.5, abs=2 * PERIOD_S)


def test_the_default_margin_is_the_mission_nodes(dead_driver):
    steps = []
    with pytest.raises(TimeoutError, match=r"within 6\.5 s .*\(1\.5 s trajectory \+ 5\.0 s"):
        scout_execute.send_through_driver(FakePlant(), None, 0.05, steps.append, PERIOD_S)
    assert len(steps) == pytest.approx(6.5 / PERIOD_S, abs=2)


@pytest.mark.parametrize("margin", [0.0, -1.0, math.inf, math.nan])
def test_the_margin_must_be_a_positive_number_of_seconds(dead_driver, margin):
    with pytest.raises(ValueError, match="result_margin_s: must be a positive number of seconds"):
        scout_execute.send_through_driver(FakePlant(), None, 0.05, lambda t: None, PERIOD_S, result_margin_s=margin)
