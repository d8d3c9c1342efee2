"""MujocoServoBackend: the plant behind the mocked bus, in servo units and by Dynamixel ID."""
import math

import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.mujoco_servo_backend import MujocoServoBackend
from snake_autonomy.sim.plant import Plant
from snake_autonomy.sim.servo_backend import ServoBackend

DIRECTIONS = [1, -1, 1, -1, 1, 1, -1, 1, 1, -1, 1]
OFFSETS = [0, 100, -50, 0, 0, 0, 0, 0, 0, 0, 2000]
IDS = [21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31]


@pytest.fixture(scope="module")
def robot(cobra_yaml):
    """COBRA with mixed servo directions, zero offsets and IDs, to exercise the mapping."""
    text = open(cobra_yaml).read()
    text = text.replace("ids: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]", f"ids: {IDS}")
    text = text.replace("directions: [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1]",
                        f"directions: {DIRECTIONS}")
    text = text.replace("zero_offsets_ticks: [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]",
                        f"zero_offsets_ticks: {OFFSETS}")
    model = _core.RobotModel.from_yaml_string(text)
    assert list(model.servo_directions) == DIRECTIONS
    return model


@pytest.fixture()
def backend(robot, root):
    params = SimConfig.from_yaml(root / "config" / "sim.yaml").draw(seed=1)
    return MujocoServoBackend(Plant(robot, params))


RAD_PER_TICK = 2 * math.pi / 4096          # XH540 reference value, independent of the code under test


def ticks(shaft_rad):
    return 2048 + shaft_rad / RAD_PER_TICK


def test_is_a_servo_backend(backend):
    assert isinstance(backend, ServoBackend)
    assert backend.ids() == IDS
    with pytest.raises(KeyError, match="servo ID 1"):
        backend.state(1)


@pytest.mark.parametrize("j", range(11))
def test_tick_mapping(backend, j):
    """ticks = 2048 + offset + direction * q / (2 pi / 4096), both ways."""
    for q in (-1.2, 0.0, 0.7):
        shaft = backend.shaft_from_joint(j, q)
        expected = 2048 + OFFSETS[j] + DIRECTIONS[j] * q / (2 * math.pi / 4096)
        assert ticks(shaft) == pytest.approx(expected)
        assert backend.joint_from_shaft(j, shaft) == pytest.approx(q)


def test_goal_moves_the_joint_and_state_reports_it(backend):
    plant = backend.plant
    j, sid = 1, IDS[1]                      # direction -1, offset 100 ticks
    goal_q = 0.5
    backend.advance(100.0)                  # pins the bus clock to plant time 0
    backend.set_goal(sid, backend.shaft_from_joint(j, goal_q))
    assert plant.joint_goals_rad()[j] == pytest.approx(goal_q)
    backend.advance(101.0)
    assert plant.time_s == pytest.approx(1.0)
    s = backend.state(sid)
    assert plant.joint_positions_rad()[j] == pytest.approx(goal_q, abs=0.05)
    assert ticks(s.position_rad) == pytest.approx(2048 + 100 - goal_q / RAD_PER_TICK, abs=40)
    # current = direction * torque / k_t
    _, _, torque = plant.joint_state(j)
    assert s.current_a == pytest.approx(-torque / 2.25)


def test_torque_off_and_on(backend):
    sid = IDS[0]
    backend.advance(0.0)
    backend.set_goal(sid, -0.6)             # joint 1 raises the head
    backend.advance(1.5)
    raised = backend.state(sid).position_rad
    assert raised == pytest.approx(-0.6, abs=0.1)
    assert abs(backend.state(sid).current_a) > 0.2
    backend.set_torque(sid, False)
    backend.advance(3.0)
    assert backend.state(sid).current_a == 0.0
    assert abs(backend.state(sid).position_rad) < 0.2         # fell back down
    backend.set_torque(sid, True)
    backend.advance(5.0)
    assert backend.state(sid).position_rad == pytest.approx(-0.6, abs=0.1)


def test_goal_beyond_limits_is_clamped(backend, robot):
    backend.set_goal(IDS[2], 100.0)
    assert backend.plant.joint_goals_rad()[2] == pytest.approx(robot.joint_upper_rad[2])


def test_long_pause_is_not_simulated(backend):
    backend.advance(10.0)
    backend.advance(10.5)
    assert backend.plant.time_s == pytest.approx(0.5)
    backend.advance(70.5)                   # 60 s gap: the world paused with the process
    assert backend.plant.time_s == pytest.approx(0.5 + backend.max_catch_up_s)
    assert backend.paused_s == pytest.approx(60.0 - backend.max_catch_up_s)
    backend.advance(70.6)
    assert backend.plant.time_s == pytest.approx(0.6 + backend.max_catch_up_s)
    backend.advance(70.0)                   # time never runs backwards
    assert backend.plant.time_s == pytest.approx(0.6 + backend.max_catch_up_s)


def test_lock_step_replays_identically(robot, root):
    """The same calls at the same (simulated) times give the same states, bit for bit."""
    def run():
        params = SimConfig.from_yaml(root / "config" / "sim.yaml").draw(seed=3)
        b = MujocoServoBackend(Plant(robot, params))
        out = []
        for k in range(200):
            t = k * 0.01
            b.advance(t)
            for j, sid in enumerate(IDS):
                b.set_goal(sid, b.shaft_from_joint(j, 0.5 * np.sin(2 * np.pi * 0.7 * t + j)))
            out.append([b.state(sid).position_rad for sid in IDS])
        return np.array(out)

    assert np.array_equal(run(), run())
