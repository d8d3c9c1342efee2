"""The bindings against an independent numpy transcription of the thesis (thesis_reference.py),
on 1000 random configurations and 1000 random gait parameter sets."""
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import thesis_reference as ref
from snake_autonomy import _core

N_RANDOM = 1000


@pytest.fixture(scope="module")
def model(cobra_yaml):
    return _core.RobotModel.from_yaml(cobra_yaml)


def random_quaternion(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


@pytest.mark.parametrize("chassis", ["mean_axis", "svd"])
def test_kinematics_matches_the_thesis_on_random_configurations(cobra_yaml, chassis):
    text = open(cobra_yaml).read().replace("virtual_chassis: mean_axis", f"virtual_chassis: {chassis}")
    model = _core.RobotModel.from_yaml_string(text)
    assert model.virtual_chassis == chassis
    kin = _core.Kinematics(model)
    rng = np.random.default_rng(2024)
    lower, upper = model.joint_lower_rad, model.joint_upper_rad
    for _ in range(N_RANDOM):
        q = rng.uniform(lower, upper)
        p = rng.uniform(-5, 5, size=3)
        # Mostly level bases (as on the ground), some fully random.
        quat = random_quaternion(rng) if rng.random() < 0.3 else np.array(
            [0, 0, np.sin(a := rng.uniform(-np.pi, np.pi)) , np.cos(a)])
        s = kin.compute(p, quat, q)
        frames = ref.forward_kinematics(model.head_length_m, model.link_length_m, q, p, quat)
        P = np.array([T[:3, 3] for T in frames])
        R = np.array([T[:3, :3] for T in frames])
        np.testing.assert_allclose(s.link_positions, P, atol=1e-10)
        np.testing.assert_allclose(s.link_rotations, R, atol=1e-10)
        com = ref.centre_of_mass(P, model.masses_kg)
        np.testing.assert_allclose(s.com, com, atol=1e-10)
        if chassis == "mean_axis":
            vc = ref.virtual_chassis_mean_axis(R)
        else:
            vc = ref.virtual_chassis_svd(P)
        np.testing.assert_allclose(s.vc_rotation, vc, atol=1e-8)
        np.testing.assert_allclose(s.bbox_span, ref.bounding_box_span(P, com, vc, 0.1), atol=1e-8)


def test_cpg_matches_the_thesis_on_random_gait_parameter_sets(model):
    """1000 random sets (amplitudes, common frequency, phases, biases, initial phases and
    amplitudes): one second of the core at 10 ms steps against RK4 at 1 ms on eq. 3.21-3.25."""
    n = model.num_joints
    rng = np.random.default_rng(7)
    A, B = ref.coupling_matrices(n)
    amp_limit = model.amplitude_limit_rad
    a_des = rng.uniform(-amp_limit, amp_limit, size=(N_RANDOM, n))
    omega = np.repeat(rng.uniform(0, 2 * np.pi * 1.5, size=(N_RANDOM, 1)), n, axis=1)
    phase = rng.uniform(-np.pi, np.pi, size=(N_RANDOM, n))
    bias = rng.uniform(-0.4, 0.4, size=(N_RANDOM, n))
    theta0 = rng.uniform(-np.pi, np.pi, size=(N_RANDOM, n))
    r0 = rng.uniform(-0.5, 0.5, size=(N_RANDOM, n))

    core_q = np.empty((N_RANDOM, n))
    core_state = np.empty((N_RANDOM, 2 * n))
    for k in range(N_RANDOM):
        cpg = _core.CPG(model)
        cpg.set_parameters(amplitude=a_des[k], omega=omega[k], phase=phase[k], bias=bias[k])
        cpg.reset(theta0[k], r0[k], bias[k])  # lags and biases start at their targets
        for _ in range(100):
            q = cpg.step(0.01)
        core_q[k] = q
        core_state[k] = np.concatenate([cpg.phases, cpg.amplitudes])

    # The core takes each new lag target as the equivalent of φ_{i+1} − φ_i (mod 2π) nearest to its
    # current lag (0 for a new CPG): the same steady state, without needless full turns.
    dphi = np.angle(np.exp(1j * np.diff(phase, axis=1)))
    state0 = np.concatenate([theta0, r0, np.zeros_like(r0)], axis=1)
    state = ref.cpg_rk4(state0, 0.001, 1000, A, B, model.mu, model.gamma, a_des, omega, dphi)
    theta, r = state[:, :n], state[:, n:2 * n]
    # The core keeps phases bounded by common whole turns: compare sin/cos, lags and amplitudes.
    np.testing.assert_allclose(np.sin(core_state[:, :n]), np.sin(theta), atol=1e-8)
    np.testing.assert_allclose(np.cos(core_state[:, :n]), np.cos(theta), atol=1e-8)
    np.testing.assert_allclose(np.diff(core_state[:, :n], axis=1), np.diff(theta, axis=1), atol=1e-8)
    np.testing.assert_allclose(core_state[:, n:], r, atol=1e-10)
    expected_q = ref.cpg_output(theta, r, bias, model.joint_lower_rad, model.joint_upper_rad)
    np.testing.assert_allclose(core_q, expected_q, atol=1e-8)


def test_steering_matches_algorithm_1(model):
    steering = _core.Steering(model)
    rng = np.random.default_rng(3)
    lim = np.radians(70)
    for _ in range(N_RANDOM):
        nominal = rng.uniform(-lim, lim, size=model.num_joints)
        delta = rng.uniform(-0.8, 0.8)
        expected = ref.modify_amplitudes(nominal, delta, model.steering_weights, model.yaw_joints,
                                         model.delta_offset_rad, -lim, lim, model.delta_limit_rad)
        np.testing.assert_allclose(steering.modify_amplitudes(nominal, delta), expected, atol=1e-12)


def test_bad_arguments_raise_clear_errors(model):
    kin = _core.Kinematics(model)
    cpg = _core.CPG(model)
    with pytest.raises(ValueError, match=r"q: expected shape \(11,\), got \(3,\)"):
        kin.compute([0, 0, 0], [0, 0, 0, 1], np.zeros(3))
    with pytest.raises(ValueError, match=r"q\[4\]: must be finite"):
        q = np.zeros(11)
        q[4] = np.nan
        kin.compute([0, 0, 0], [0, 0, 0, 1], q)
    with pytest.raises(ValueError, match="base_quaternion_xyzw: must not be zero"):
        kin.compute([0, 0, 0], [0, 0, 0, 0], np.zeros(11))
    with pytest.raises(ValueError, match="base_position: expected an array of numbers"):
        kin.compute("abc", [0, 0, 0, 1], np.zeros(11))
    before = cpg.targets.amplitude.copy()
    with pytest.raises(ValueError, match=r"omega\[2\]: must be finite"):
        cpg.set_parameters(amplitude=np.full(11, 0.3), omega=[0, 0, np.inf] + [0] * 8)
    np.testing.assert_array_equal(cpg.targets.amplitude, before)  # refused whole
    with pytest.raises(ValueError, match="dt_s: must be a positive finite number"):
        cpg.step(0.0)


def test_unknown_gait_is_a_key_error(root, model):
    lib = _core.GaitLibrary.from_yaml(str(root / "config" / "gaits.yaml"))
    with pytest.raises(KeyError, match="unknown gait 'moonwalk'"):
        lib.parameters("moonwalk", model)


def test_urdf_names_every_frame(model):
    robot = ET.fromstring(_core.make_urdf(model))
    links = {link.get("name") for link in robot.findall("link")}
    assert set(model.frame_names) <= links
    revolute = [j.get("name") for j in robot.findall("joint") if j.get("type") == "revolute"]
    assert revolute == list(model.joint_names)
