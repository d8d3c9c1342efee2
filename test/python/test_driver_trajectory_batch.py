"""Trajectory execution through the batch driver: a planned FBSR trajectory handed to the
C++ DriverController (command_trajectory, the TrajectorySource driver_node runs on
driver/joint_trajectory), executed in lock-step on the MuJoCo plant, reaches its final posture and is
held there; a bad trajectory is refused whole with its reasons and nothing moves."""
import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.trajectory import plan_points
from snake_autonomy.runs.batch import LockStepDriver, load_driver_config
from snake_autonomy.sim.config import SimConfig, servo_torque_limit_nm
from snake_autonomy.sim.plant import Plant
from snake_autonomy.runs.scout_executor import DriverTrajectoryExecutor

DT = 0.01
#: Measured joint error once held (seed 0, 4 active modules): at most 0.0047 rad, the simulated
#: servos' proportional sag under the raised portion's weight at the most loaded base joints; the
#: goals themselves equal the last point. Twice that, rounded up.
JOINT_TOLERANCE_RAD = 0.01
#: Head height against the plan, measured within 1 mm: the joint sag above, over the short lever.
HEAD_TOLERANCE_M = 0.01


@pytest.fixture(scope="module")
def rig(root):
    planner = build_planner(str(root / "config/robots/unified_snake.yaml"), torque_limit_nm=servo_torque_limit_nm())[0]
    plan = planner.plan(max_active=4, seed=0)
    robot = planner.chain.robot
    params = SimConfig.from_yaml(root / "config/sim.yaml").draw(0, num_joints=robot.num_joints)
    start = planner.chain.pose(planner.chain.q_lying)
    heading = float(np.arctan2(start.rotations[0][1, 0], start.rotations[0][0, 0]))
    plant = Plant(robot, params, start=(*start.positions[0, :2], heading), q0_rad=planner.chain.q_lying)
    plant.step(1.0)
    library = _core.GaitLibrary.from_yaml(str(root / "config/gaits.yaml"))
    driver = LockStepDriver(robot, library, plant, load_driver_config(root / "config/driver.yaml"))
    return plan, plant, driver


def run_for(plant, driver, cycles):
    for _ in range(cycles):
        t = plant.time_s + DT
        plant.step_to(t)
        driver.update(t, DT)


def test_a_bad_trajectory_is_refused_whole_and_nothing_moves(rig):
    plan, plant, driver = rig
    c = driver.controller
    before = np.array(c.goal_rad)
    n = plant.num_joints
    names = [f"joint_{j + 1}" for j in range(n)]
    names[2] = "joint_2"
    q = np.zeros((2, n))
    q[1, 0] = 3.0
    why = c.command_trajectory(names, [0.5, 0.5], q, id="bad")
    for part in ("joint_names[2]: 'joint_2' repeats joint_names[1]", "joint_names: joint_3 is missing",
                 "points[1].positions[0] (joint_1): 3 rad outside the joint limits",
                 "points[1].time_from_start: 0.5 s, not after points[0]"):
        assert part in why, why
    run_for(plant, driver, 20)
    assert c.state == "holding" and c.trajectory_progress["phase"] == "idle"
    np.testing.assert_array_equal(c.goal_rad, before)
    with pytest.raises(ValueError, match="positions_rad must be"):
        c.command_trajectory(names, [0.5], q)


def test_a_planned_fbsr_trajectory_reaches_its_final_posture_through_the_driver(rig):
    plan, plant, driver = rig
    traj = plan_points(plan, 0.05, lead_in=1.0)
    executor = DriverTrajectoryExecutor(driver.controller)
    assert executor.execute(traj, plant.time_s) == ""
    assert not executor.finished(plant.time_s)          # handed over, not yet taken
    cycles = 0
    while not executor.finished(plant.time_s):
        run_for(plant, driver, 1)
        cycles += 1
        assert cycles <= int((traj.duration_s + 1.0) / DT), driver.controller.trajectory_progress
    c = driver.controller
    progress = c.trajectory_progress
    assert progress["phase"] == "done" and executor.aborted == ""
    assert progress["point_reached"] == len(traj.points) - 1 == progress["num_points"] - 1
    assert progress["time_s"] == pytest.approx(traj.duration_s)
    assert c.state == "holding" and "trajectory done" in c.hold_reason
    run_for(plant, driver, 100)                         # held for 1 s
    final = traj.final_positions_rad
    np.testing.assert_allclose(c.goal_rad, final, atol=2 * np.pi / 4096)   # within the tick clamp
    np.testing.assert_allclose(plant.joint_positions_rad(), final, atol=JOINT_TOLERANCE_RAD)
    assert plant.frame_positions()[0][2] == pytest.approx(plan.final_head_height_m, abs=HEAD_TOLERANCE_M)
    assert plant.limit_violations == 0


class _StuckController:
    """A driver that takes a trajectory and never ends it (it stopped stepping mid-way)."""
    ids = list(range(1, 12))

    def __init__(self):
        self.trajectory_progress = {"sequence": 0, "phase": "idle", "abort": "", "reason": ""}

    def command_trajectory(self, names, times, q, v, id=""):
        self.trajectory_progress = {"sequence": 1, "phase": "running", "abort": "", "reason": ""}
        return ""


def test_a_trajectory_the_driver_never_ends_is_given_up_after_its_duration_and_the_margin(rig):
    plan = rig[0]
    traj = plan_points(plan, 0.05, lead_in=1.0)
    executor = DriverTrajectoryExecutor(_StuckController(), result_margin_s=2.0)
    assert executor.execute(traj, 10.0) == ""
    deadline = 10.0 + traj.duration_s + 2.0
    assert not executor.finished(deadline - 0.01) and executor.aborted == ""
    assert executor.finished(deadline + 0.01)
    assert "no final phase for trajectory 'scout 1'" in executor.aborted
    assert f"within {traj.duration_s + 2.0:.1f} s" in executor.aborted and "phase 'running'" in executor.aborted
    assert executor.gave_up
