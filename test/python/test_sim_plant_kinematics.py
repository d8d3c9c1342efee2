"""The plant's link frames are the thesis's kinematic frames (eq. 3.3-3.4), at random angles.

Two references: a direct numpy transcription of eq. 3.3-3.4 written here, independent of the
MJCF generator, and the core's KDL kinematics (_core.Kinematics).
"""
import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.plant import Plant
from snake_autonomy.transforms import quat_to_matrix, rot_x, rot_z


def _trans(x, y, z):
    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t


def _rot(r):
    t = np.eye(4)
    t[:3, :3] = r
    return t


def thesis_fk(robot, base, q):
    """Eq. 3.3: head = base . Trans(-H,0,0) . Rx(+90); eq. 3.4: link_i = link_{i-1} . Rz(-q_i) .
    Trans(-L,0,0) . Rx(-90 after a pitch joint, +90 after a yaw joint)."""
    frames = [base, base @ _trans(-robot.head_length_m, 0, 0) @ _rot(rot_x(np.pi / 2))]
    for i, axis in enumerate(robot.axes):
        twist = -np.pi / 2 if axis == "pitch" else np.pi / 2
        frames.append(frames[-1] @ _rot(rot_z(-q[i])) @ _trans(-robot.link_length_m, 0, 0)
                      @ _rot(rot_x(twist)))
    return frames


@pytest.fixture(scope="module")
def robot(cobra_yaml):
    return _core.RobotModel.from_yaml(cobra_yaml)


@pytest.fixture(scope="module")
def plant(robot):
    return Plant(robot, SimConfig().draw(seed=0, randomize=False))


def _random_base(rng):
    base = np.eye(4)
    axis = rng.normal(size=3)
    angle = rng.uniform(-np.pi, np.pi)
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    base[:3, :3] = np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx
    base[:3, 3] = rng.uniform(-2, 2, size=3)
    return base


def test_frames_match_eq_3_3_and_3_4(robot, plant):
    rng = np.random.default_rng(42)
    lower, upper = np.asarray(robot.joint_lower_rad), np.asarray(robot.joint_upper_rad)
    for _ in range(20):
        q = rng.uniform(lower, upper)
        base = _random_base(rng)
        plant.set_configuration(q, base=base)
        expected = thesis_fk(robot, base, q)
        for name, t_exp in zip(robot.frame_names, expected):
            t = plant.frame_transform(name)
            np.testing.assert_allclose(t[:3, 3], t_exp[:3, 3], atol=1e-9, err_msg=name)
            np.testing.assert_allclose(t[:3, :3], t_exp[:3, :3], atol=1e-9, err_msg=name)
            p, quat = plant.frame_pose(name)
            np.testing.assert_allclose(quat_to_matrix(*quat), t_exp[:3, :3], atol=1e-9)


def test_axis_convention(robot, plant):
    """Base z up: the body extends along -x, joint 1 pitches (the tail leaves the ground plane),
    joint 2 yaws (the tail stays in it)."""
    plant.set_configuration(np.zeros(robot.num_joints), base=np.eye(4))
    tail = plant.frame_positions()[-1]
    assert tail[0] < -1.4 and abs(tail[1]) < 1e-9 and abs(tail[2]) < 1e-9
    q = np.zeros(robot.num_joints)
    q[0] = 0.3
    plant.set_configuration(q, base=np.eye(4))
    assert abs(plant.frame_positions()[-1][2]) > 0.1           # pitch: out of the ground plane
    q[:] = 0
    q[1] = 0.3
    plant.set_configuration(q, base=np.eye(4))
    tail = plant.frame_positions()[-1]
    assert abs(tail[2]) < 1e-9 and abs(tail[1]) > 0.1          # yaw: within the ground plane


def test_core_kinematics_agrees(robot, plant):
    """The plant's frames are the core's (KDL) frames too, at random angles and base poses."""
    kin = _core.Kinematics(robot)
    rng = np.random.default_rng(7)
    for _ in range(10):
        q = rng.uniform(robot.joint_lower_rad, robot.joint_upper_rad)
        base = _random_base(rng)
        plant.set_configuration(q, base=base)
        p, quat = plant.frame_pose("base_link")
        state = kin.compute(p, quat, q)
        for i, name in enumerate(robot.frame_names):
            t = plant.frame_transform(name)
            np.testing.assert_allclose(t[:3, 3], state.link_positions[i], atol=1e-9, err_msg=name)
            np.testing.assert_allclose(t[:3, :3], state.link_rotations[i], atol=1e-9,
                                       err_msg=name)
        np.testing.assert_allclose(plant.frame_positions(), state.link_positions, atol=1e-9)
