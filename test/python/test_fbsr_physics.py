"""FBSR in physics (MuJoCo plant): the centre of pressure of a robot at rest is its CoG, and a short
plan executed as servo goals does not tip the robot and reaches the planned head height."""
import dataclasses

import mujoco
import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.planning.fbsr import collision
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.runs.scout_execute import centre_of_pressure, run_plan, self_contacts
from snake_autonomy.sim.config import SimConfig, servo_torque_limit_nm
from snake_autonomy.sim.plant import Plant


def test_centre_of_pressure_of_a_robot_at_rest_is_under_its_centre_of_gravity(root):
    robot = _core.RobotModel.from_yaml(str(root / "config/robots/unified_snake.yaml"))
    params = SimConfig.from_yaml(root / "config/sim.yaml").draw(0, num_joints=robot.num_joints)
    q0 = np.zeros(robot.num_joints)
    q0[1::2] = 0.5                       # yaw joints: a curled body, contacts spanning an area
    plant = Plant(robot, params, q0_rad=q0)
    plant.step(1.0)
    floor = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    cop, contacts = centre_of_pressure(plant.model, plant.data, floor)
    assert len(contacts) >= 3
    np.testing.assert_allclose(cop, plant.center_of_mass()[:2], atol=0.003)


def test_short_plan_executed_in_physics_does_not_tip(root):
    planner = build_planner(str(root / "config/robots/unified_snake.yaml"), torque_limit_nm=servo_torque_limit_nm())[0]
    plan = planner.plan(max_active=4, seed=0)
    result = run_plan(plan, root / "config/sim.yaml", seed=0)
    m = result["metrics"]
    assert m["tipped"] is False
    assert m["cop_inside_fraction"] == 1.0
    assert m["active_modules"] == 4
    assert m["final_head_height_m"] == pytest.approx(m["planned_head_height_m"], abs=0.02)
    assert 0 < m["max_torque_ratio"] < 1.0
    assert result["extra"]["limit_violations"] == 0
    assert result["extra"]["self_contact_steps"] == 0


def test_links_that_are_not_neighbours_collide_in_the_scout_plant(root):
    """physics.self_collision (on for scout runs): joints 2-6 at 1.2 rad coil the body so that the
    head's capsule reaches 17 mm into link_7's (collision.py): a contact with it on, none with it
    off; neighbours, which share a joint and touch there, never make one."""
    robot = _core.RobotModel.from_yaml(str(root / "config/robots/unified_snake.yaml"))
    sim = SimConfig.from_yaml(root / "config/sim.yaml")
    q0 = np.zeros(robot.num_joints)
    q0[1:6] = 1.2
    counts = {}
    for on in (False, True):
        cfg = dataclasses.replace(sim, physics=dataclasses.replace(sim.physics, self_collision=on))
        plant = Plant(robot, cfg.draw(0, num_joints=robot.num_joints), q0_rad=q0)
        model, data = plant.model, plant.data
        mujoco.mj_forward(model, data)
        counts[on] = self_contacts(model, data)
        body = model.geom_bodyid
        pairs = [(body[c.geom1], body[c.geom2]) for c in data.contact[:data.ncon]]
        robot_pairs = [(a, b) for a, b in pairs if a and b]
        assert len(robot_pairs) == counts[on]
        assert not any(model.body_parentid[a] == b or model.body_parentid[b] == a for a, b in robot_pairs)
    assert counts[False] == 0 and counts[True] > 0


def test_cli_run_writes_metrics_with_the_contract_keys(tmp_path):
    import json

    from snake_autonomy import cli

    out = tmp_path / "run"
    assert cli.main(["scout", "run", "--robot", "unified_snake", "--max-active", "2",
                     "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert set(m) == {"tipped", "outcome", "cop_inside_fraction", "final_head_height_m",
                      "planned_head_height_m", "max_torque_ratio", "active_modules"}
    assert m["tipped"] is False and m["outcome"] == "ok" and m["active_modules"] == 2
    assert (out / "plan.json").is_file()


def test_cobra_raise_makes_no_link_link_contact_in_physics(root):
    """COBRA's tail once curled to 3.3 mm of module 2 (config/scout.yaml's lying posture): the plan
    kept that gap, but the first raise's load on the servos closed it in physics and modules 2 and
    11 touched for 193 steps (seed 1). The lying posture must leave room for the servos to give."""
    planner = build_planner("cobra", torque_limit_nm=servo_torque_limit_nm())[0]
    plan = planner.plan(seed=1)
    result = run_plan(plan, root / "config/sim.yaml", seed=1)
    assert result["extra"]["self_contact_steps"] == 0
    assert result["metrics"]["outcome"] == "ok", result["extra"]["reason"]


def test_the_planners_capsules_are_the_plants_link_geoms(root):
    """The planner's clearance of every non-adjacent pair of modules equals MuJoCo's distance
    between the two link geoms (same radius, same end points), in COBRA's lying posture."""
    planner = build_planner("cobra", torque_limit_nm=servo_torque_limit_nm())[0]
    chain = planner.chain
    pose = chain.pose(chain.q_lying)
    heading = float(np.arctan2(pose.rotations[0][1, 0], pose.rotations[0][0, 0]))
    params = SimConfig.from_yaml(root / "config/sim.yaml").draw(0, num_joints=chain.num_joints)
    plant = Plant(chain.robot, params, start=(*pose.positions[0, :2], heading), q0_rad=chain.q_lying)
    model, data = plant.model, plant.data
    mujoco.mj_forward(model, data)
    geoms = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
             for name in ["head"] + [f"link_{i + 1}" for i in range(chain.num_joints)]]
    pairs = collision.module_pairs(chain.num_modules)
    planned = collision.clearances(pose.positions, chain.radius_m, pairs)
    fromto = np.zeros(6)
    plant_m = [mujoco.mj_geomDistance(model, data, geoms[i], geoms[j], 1.0, fromto) for i, j in pairs]
    np.testing.assert_allclose(plant_m, planned, atol=1e-6)
