"""A plan as the driver's joint trajectory: points, the driver's velocity limit, the ROS message, the
CLI's trajectory.json and --lower."""
import json

import numpy as np
import pytest

from snake_autonomy import cli
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.planner import lowering
from snake_autonomy.planning.fbsr.trajectory import (JointTrajectoryPoints, TrajectoryPoint, driver_joint_names,
                                                     driver_velocity_limit, lead_in_s, plan_points,
                                                     velocity_problems)
from snake_autonomy.sim.config import servo_torque_limit_nm


@pytest.fixture(scope="module")
def planned(root):
    planner = build_planner(str(root / "config/robots/unified_snake.yaml"), torque_limit_nm=servo_torque_limit_nm())[0]
    return planner, planner.plan(max_active=4, seed=0)


def test_points_follow_the_plan_after_the_lead_in(planned):
    planner, plan = planned
    traj = plan_points(plan, 0.05, lead_in=1.5)
    assert traj.joint_names == [f"joint_{i}" for i in range(1, 17)]
    t = np.array([p.time_from_start_s for p in traj.points])
    assert t[0] == pytest.approx(1.5) and np.all(np.diff(t) > 0) and np.diff(t).max() <= 0.05 + 1e-9
    assert traj.duration_s == pytest.approx(1.5 + plan.duration_s)
    np.testing.assert_allclose(traj.points[0].positions_rad, planner.chain.q_lying, atol=1e-12)
    np.testing.assert_allclose(traj.final_positions_rad, plan.q_end, atol=1e-12)
    # listed velocities are the cubics' derivatives: rest at both ends, matching finite differences
    q = np.array([p.positions_rad for p in traj.points])
    v = np.array([p.velocities_rad_s for p in traj.points])
    assert np.abs(v[0]).max() == 0.0 and np.abs(v[-1]).max() < 1e-9
    mid = (q[2:] - q[:-2]) / (t[2:] - t[:-2])[:, None]
    np.testing.assert_allclose(v[1:-1], mid, atol=0.02)


def test_plan_and_its_lowering_respect_the_drivers_velocity_limit(planned, root):
    planner, plan = planned
    vmax = driver_velocity_limit(root / "config/driver.yaml")
    assert vmax == pytest.approx(4.5)
    up = plan_points(plan, 0.05, lead_in_s(planner.chain.lower, planner.chain.upper, vmax))
    assert velocity_problems(up, vmax) == []
    # from any posture inside the limits, the lead-in is slow enough
    assert velocity_problems(up, vmax, q_from=planner.chain.upper) == []
    assert velocity_problems(up, vmax, q_from=planner.chain.lower) == []
    down = plan_points(lowering(plan), 0.05)
    assert velocity_problems(down, vmax, q_from=up.final_positions_rad) == []
    np.testing.assert_allclose(down.final_positions_rad, planner.chain.q_lying, atol=1e-12)


def test_velocity_check_refuses_fast_or_disordered_points():
    names = driver_joint_names(2)
    fast = JointTrajectoryPoints(names, [TrajectoryPoint(0.1, (0.0, 0.0), (0.0, 0.0)),
                                         TrajectoryPoint(0.2, (0.5, 0.0), (0.0, 0.0))])
    found = velocity_problems(fast, 4.5)
    assert len(found) == 1 and "joint_1 between t = 0.100 and 0.200" in found[0]
    listed = JointTrajectoryPoints(names, [TrajectoryPoint(1.0, (0.0, 0.0), (0.0, 5.0))])
    assert "velocity is 5.00" in velocity_problems(listed, 4.5)[0]
    backwards = JointTrajectoryPoints(names, [TrajectoryPoint(1.0, (0.0, 0.0), (0.0, 0.0)),
                                              TrajectoryPoint(0.5, (0.0, 0.0), (0.0, 0.0))])
    assert "strictly increasing" in velocity_problems(backwards, 4.5)[0]
    # a lead-in from far away needs time: 1 s is too short for 3 rad
    slow = JointTrajectoryPoints(names, [TrajectoryPoint(1.0, (3.0, 0.0), (0.0, 0.0))])
    assert velocity_problems(slow, 4.5, q_from=(0.0, 0.0))
    assert lead_in_s((0.0, 0.0), (3.0, 0.0), 4.5) > 1.0


def test_ros_message_carries_names_positions_and_times(planned):
    pytest.importorskip("trajectory_msgs")
    from snake_autonomy.nodes.scout_trajectory import to_msg

    _, plan = planned
    traj = plan_points(plan, 0.05, lead_in=2.0)
    msg = to_msg(traj)
    assert msg.joint_names == traj.joint_names and len(msg.points) == len(traj.points)
    assert msg.points[0].time_from_start.to_sec() == pytest.approx(2.0)
    assert msg.points[-1].time_from_start.to_sec() == pytest.approx(traj.duration_s)
    np.testing.assert_allclose(msg.points[-1].positions, traj.final_positions_rad)


def test_cli_writes_the_trajectory_and_its_lowering(tmp_path, root):
    up, down = tmp_path / "up", tmp_path / "down"
    args = ["scout", "plan", "--robot", "unified_snake", "--max-active", "2", "--seed", "3"]
    assert cli.main(args + ["--out", str(up)]) == 0
    assert cli.main(args + ["--lower", "--out", str(down)]) == 0
    t_up = json.loads((up / "trajectory.json").read_text())
    t_down = json.loads((down / "trajectory.json").read_text())
    assert t_up["joint_names"][0] == "joint_1" and len(t_up["points"][0]["positions_rad"]) == 16
    np.testing.assert_allclose(t_down["points"][0]["positions_rad"], t_up["points"][-1]["positions_rad"])
    np.testing.assert_allclose(t_down["points"][-1]["positions_rad"], t_up["points"][0]["positions_rad"],
                               atol=1e-12)
    up_plan = json.loads((up / "plan.json").read_text())
    down_plan = json.loads((down / "plan.json").read_text())
    assert down_plan["final_head_height_m"] < 0.05 < up_plan["final_head_height_m"]
