"""The pipe scenario (paper fig. 6): the head goes into a pipe hanging with its mouth 0.25 m up and
stays inside its bore in physics, or the plan is refused with where the head ended
(test_scout_outcomes.py); the pipe's wall touching the robot is no link-link contact."""
import dataclasses

import mujoco
import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.cost import Pipe
from snake_autonomy.planning.fbsr.pipe_scene import head_in_mouth, pipe_mjcf
from snake_autonomy.planning.fbsr.planner import PIPE_DEPTH_M
from snake_autonomy.planning.fbsr.stage import PlanningError
from snake_autonomy.runs.scout_execute import run_plan, self_contacts
from snake_autonomy.sim.config import SimConfig, servo_torque_limit_nm
from snake_autonomy.sim.plant import Plant


def test_a_pipe_plan_puts_the_head_past_the_mouth_and_physics_keeps_it_in_the_bore(root):
    planner = build_planner("unified_snake", torque_limit_nm=servo_torque_limit_nm())[0]
    pipe = Pipe(0.05, -0.10, 0.07)
    plan = planner.plan(seed=0, pipe=pipe)
    c = planner.cfg.pipe_clearance_m
    assert head_in_mouth(plan.chain.pose(plan.q_end).head, pipe, plan.chain.radius_m, PIPE_DEPTH_M, c)
    result = run_plan(plan, root / "config/sim.yaml", seed=0, pipe=pipe)
    extra = result["extra"]
    assert result["metrics"]["outcome"] == "ok", extra["reason"]
    assert extra["head_in_bore"] is True and extra["head_to_pipe_axis_m"] < extra["bore_limit_m"]
    assert result["metrics"]["final_head_height_m"] > pipe.mouth_m
    assert extra["self_contact_steps"] == 0 and extra["air_load_fraction"] < 0.01


def test_the_pipe_wall_against_the_robot_is_not_a_self_contact(root):
    """A pipe standing on the floor (mouth at 0) whose wall crosses the lying body: contacts
    between the wall and links, none of them counted as link-link."""
    robot = _core.RobotModel.from_yaml(str(root / "config/robots/unified_snake.yaml"))
    params = SimConfig.from_yaml(root / "config/sim.yaml").draw(0, num_joints=robot.num_joints)
    plant = Plant(robot, params, q0_rad=np.zeros(robot.num_joints),
                  scene_xml=pipe_mjcf(Pipe(-0.3, 0.0, 0.07, mouth_m=0.0)))
    model, data = plant.model, plant.data
    mujoco.mj_forward(model, data)
    pipe_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "pipe")
    with_wall = [c for c in data.contact[:data.ncon]
                 if pipe_body in (model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2])]
    assert len(with_wall) > 0
    assert self_contacts(model, data) == 0


def _off_axis_m(plan, pipe):
    head = plan.chain.pose(plan.q_end).head
    return float(np.hypot(head[0] - pipe.x_m, head[1] - pipe.y_m)), float(head[2])


def test_a_head_planned_nearer_the_bores_edge_than_the_clearance_is_re_targeted_or_refused():
    """Without a clearance COBRA's head ends 16 mm off this pipe's axis, 19 mm inside the bore's
    edge (R 80 mm less a 45 mm module). Asked for 25 mm of clearance, the plan must end the head
    within 10 mm of the axis and 20 mm past the mouth, or be refused naming the clearance."""
    planner = build_planner("cobra", torque_limit_nm=servo_torque_limit_nm())[0]
    pipe = Pipe(0.22, 0.20, 0.08)
    bore_m = pipe.radius_m - planner.chain.radius_m
    planner.cfg = dataclasses.replace(planner.cfg, pipe_clearance_m=0.0)
    d, _ = _off_axis_m(planner.plan(seed=0, pipe=pipe), pipe)
    assert bore_m - 0.025 < d < bore_m       # in the bore, nearer its edge than 25 mm
    planner.cfg = dataclasses.replace(planner.cfg, pipe_clearance_m=0.025)
    try:
        plan = planner.plan(seed=0, pipe=pipe)
    except PlanningError as err:
        assert "less pipe_clearance_m 0.025 m" in str(err)
    else:
        d, z = _off_axis_m(plan, pipe)
        assert d < bore_m - 0.025 and z > pipe.mouth_m + PIPE_DEPTH_M


def test_a_pipe_too_narrow_for_the_clearance_is_refused_before_planning():
    planner = build_planner("cobra", torque_limit_nm=servo_torque_limit_nm())[0]
    planner.cfg = dataclasses.replace(planner.cfg, pipe_clearance_m=0.04)
    with pytest.raises(PlanningError, match="leaves no room for the head with pipe_clearance_m 0.04 m"):
        planner.plan(seed=0, pipe=Pipe(0.14, 0.15, 0.08))
