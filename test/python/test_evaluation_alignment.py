"""Yaw-only (4-DoF) alignment: closed form, recovers a known yaw + translation, never tilts."""
import numpy as np
import pytest

from snake_autonomy.evaluation import EvaluationError, EvaluationOptions, evaluate, trajectory_from_arrays
from snake_autonomy.evaluation.alignment import rot_z, yaw_alignment


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _path(n=400, seed=0):
    """A wandering 3-D path (m) with height changes, and headings along it."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 40.0, n)
    xyz = np.stack([3 * np.sin(0.15 * t) + 0.2 * t, 2 * np.cos(0.11 * t), 0.3 * np.sin(0.4 * t)], axis=1)
    xyz += rng.normal(0, 0.002, xyz.shape)
    return t, xyz


def _quat_xyzw(rotations):
    from scipy.spatial.transform import Rotation
    return Rotation.from_matrix(rotations).as_quat()


def test_recovers_known_yaw_and_translation_with_noise():
    rng = np.random.default_rng(1)
    _, ref = _path()
    theta_true, t_true = np.radians(37.0), np.array([1.5, -0.7, 0.25])
    # est expressed in a frame rotated by -theta about z and shifted: Rz(theta) est + t = ref
    est = (rot_z(theta_true).T @ (ref - t_true).T).T + rng.normal(0, 0.005, ref.shape)
    theta, t = yaw_alignment(est, ref)
    assert np.degrees(theta) == pytest.approx(37.0, abs=0.05)
    assert t == pytest.approx(t_true, abs=0.005)


def test_closed_form_is_the_least_squares_minimum():
    from scipy.optimize import minimize

    rng = np.random.default_rng(2)
    est = rng.normal(0, 1, (50, 3))
    ref = (rot_z(2.5) @ est.T).T + [3, 1, -2] + rng.normal(0, 0.3, (50, 3))

    def cost(x):
        return np.sum(((rot_z(x[0]) @ est.T).T + x[1:] - ref) ** 2)

    theta, t = yaw_alignment(est, ref)
    best = cost(np.r_[theta, t])
    for start in (0.0, 2.0, -2.0, 3.0):
        numeric = minimize(cost, np.r_[start, 0, 0, 0], method="BFGS", options={"gtol": 1e-10})
        assert best <= numeric.fun + 1e-9
    assert np.degrees(theta) == pytest.approx(np.degrees(2.5), abs=2.0)


def test_yaw_alignment_never_rotates_roll_or_pitch_unlike_se3():
    """The estimate's world is tilted by 4 deg of roll (a gravity error): SE(3) alignment removes the
    tilt, yaw alignment must keep it (only a rotation about z), so the tilt shows up in the error."""
    stamps, ref = _path()
    tilt = _rot_x(np.radians(4.0))
    yaw0 = rot_z(np.radians(-60.0))
    world_est = yaw0 @ tilt                           # est world = ref world rotated by yaw and roll
    est = (world_est.T @ (ref - [0.5, 0.2, 0.1]).T).T
    headings = [rot_z(0.3 * k / len(stamps)) for k in range(len(stamps))]
    ref_rot = np.array(headings)
    est_rot = np.array([world_est.T @ r for r in headings])
    ref_in = trajectory_from_arrays(stamps, ref, _quat_xyzw(ref_rot), name="ref")
    est_in = trajectory_from_arrays(stamps, est, _quat_xyzw(est_rot), name="est")

    yaw = evaluate(ref_in, est_in, EvaluationOptions(align="yaw", relation="angle_deg"))
    se3 = evaluate(ref_in, est_in, EvaluationOptions(align="se3", relation="angle_deg"))
    r_yaw, r_se3 = yaw.alignment[:3, :3], se3.alignment[:3, :3]
    # yaw: a pure rotation about z (z axis untouched), with the right yaw
    assert r_yaw[:, 2] == pytest.approx([0, 0, 1], abs=1e-12)
    assert r_yaw[2, :] == pytest.approx([0, 0, 1], abs=1e-12)
    assert yaw.to_dict()["alignment_yaw_deg"] == pytest.approx(-60.0, abs=0.5)
    # SE(3) tilts the z axis by the roll error, and so hides it from the rotation error
    assert np.degrees(np.arccos(r_se3[2, 2])) == pytest.approx(4.0, abs=0.05)
    assert se3.stats["max"] < 0.1
    # after yaw alignment every pose still shows the 4 deg gravity error
    assert yaw.stats["min"] == pytest.approx(4.0, abs=0.5)
    assert yaw.stats["mean"] == pytest.approx(4.0, abs=0.5)


def test_yaw_alignment_needs_three_pairs_and_spread():
    with pytest.raises(EvaluationError, match="at least 3"):
        yaw_alignment(np.zeros((2, 3)), np.zeros((2, 3)))
    vertical = np.array([[0, 0, 0], [0, 0, 1], [0, 0, 2.0]])
    with pytest.raises(EvaluationError, match="undetermined"):
        yaw_alignment(vertical, vertical + 1)
