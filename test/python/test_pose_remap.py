"""Eq. 3.1 with hand-built transforms whose answer is known, and lost-tracking detection."""
import math

import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.estimation import (GateParams, PoseRemapper, TrackingGate, head_in_base,
                                       load_camera_calibration, load_gate_params)
from snake_autonomy.transforms import (invert, make_transform, matrix_to_pose, matrix_to_quat,
                                                  pose_to_matrix, quat_to_matrix, rot_x, rot_z, rpy_to_matrix,
                                                  translation, yaw_of_quat)

H = 0.1565
DEG = math.pi / 180


def test_eq_3_3_head_in_base():
    T = head_in_base(H)
    assert T[:3, 3] == pytest.approx([-H, 0, 0])
    # Rx(+90 deg): the head's y axis is the base's z axis, the head's z axis is the base's -y axis
    assert T[:3, 1] == pytest.approx([0, 0, 1])
    assert T[:3, 2] == pytest.approx([0, -1, 0])


def test_identity_calibration_identity_odometry():
    # camera == head; base = head . inverse(Trans(-H) Rx(90)) = Rx(-90) Trans(+H): origin at (H, 0, 0)
    r = PoseRemapper(np.eye(4), H)
    T = r.base_in_world(np.eye(4))
    assert T[:3, 3] == pytest.approx([H, 0, 0])
    assert T[:3, :3] == pytest.approx(rot_x(-math.pi / 2))


def test_level_camera_at_a_known_pose():
    # The default calibration (a level camera at the head origin, rpy -90 0 0): a camera at
    # (1, 2, 0.1) with yaw 30 deg puts the base H ahead of it along the heading, level, yaw 30 deg.
    r = PoseRemapper(make_transform(rpy_to_matrix(-math.pi / 2, 0, 0)), H)
    cam = make_transform(rot_z(30 * DEG), [1.0, 2.0, 0.1])
    T = r.base_in_world(cam)
    assert T[:3, 3] == pytest.approx([1 + H * math.cos(30 * DEG), 2 + H * math.sin(30 * DEG), 0.1])
    assert T[:3, :3] == pytest.approx(rot_z(30 * DEG), abs=1e-12)
    _, q = matrix_to_pose(T)
    assert yaw_of_quat(*q) == pytest.approx(30 * DEG)


def test_offset_calibration_is_consistent_with_eq_3_3():
    calib = make_transform(rpy_to_matrix(-math.pi / 2 + 0.1, 0.05, -0.02), [0.03, -0.01, 0.02])
    r = PoseRemapper(calib, H)
    cam = make_transform(rpy_to_matrix(0.2, -0.1, 2.5), [3.0, -1.0, 0.4])
    base = r.base_in_world(cam)
    head = base @ head_in_base(H)                       # eq. 3.3 forward
    assert head @ calib == pytest.approx(cam)           # the camera where the odometry says it is
    assert r.head_in_world(cam) == pytest.approx(head)
    # the camera moved 1 m along its own x axis: the base moves 1 m along the same world direction
    moved = r.base_in_world(cam @ translation(1.0, 0, 0))
    assert moved[:3, 3] - base[:3, 3] == pytest.approx(cam[:3, 0])


def test_head_length_comes_from_the_robot_model(cobra_yaml):
    assert _core.RobotModel.from_yaml(cobra_yaml).head_length_m == pytest.approx(H)


def test_quaternion_round_trip():
    for rpy in [(0, 0, 0), (0.1, -0.2, 3.0), (math.pi, 0, 0), (0, math.pi / 2, 0), (-2.0, 0.3, -3.1)]:
        R = rpy_to_matrix(*rpy)
        q = matrix_to_quat(R)
        assert quat_to_matrix(*q) == pytest.approx(R, abs=1e-12)
    T = pose_to_matrix((1, 2, 3), (0, 0, math.sin(0.25), math.cos(0.25)))
    assert invert(T) @ T == pytest.approx(np.eye(4))
    assert yaw_of_quat(*matrix_to_pose(T)[1]) == pytest.approx(0.5)


def test_bad_calibration_is_refused(tmp_path):
    with pytest.raises(ValueError, match="camera_in_head: rotation part is not a rotation matrix"):
        PoseRemapper(np.diag([2.0, 1, 1, 1]), H)
    with pytest.raises(ValueError, match="head_length_m: must be a positive number, got 0"):
        PoseRemapper(np.eye(4), 0)
    message = refused(load_camera_calibration, tmp_path,
                      "camera_in_head: {translation_m: [0, 0], quaternion_xyzw: [0, 0, 0, 0]}")
    assert "translation_m: expected 3 finite numbers, got [0, 0]" in message
    assert "quaternion_xyzw: quaternion: must be finite and non-zero" in message


def refused(loader, tmp_path, text: str) -> str:
    """The ValueError message of loader on a camera.yaml holding text."""
    f = tmp_path / "cam.yaml"
    f.write_text(text + "\n")
    with pytest.raises(ValueError) as err:
        loader(f)
    return str(err.value)


def test_provided_camera_config(root):
    c = load_camera_calibration(root / "config" / "camera.yaml")
    assert c.camera_in_head[:3, :3] == pytest.approx(rot_x(-math.pi / 2))
    assert c.calibrated is False
    assert load_gate_params(root / "config" / "camera.yaml").lost_covariance == 1000.0


# ---- lost tracking ------------------------------------------------------------------------------
IDQ = (0.0, 0.0, 0.0, 1.0)
COV = (0.01,) * 6


def gate(**kw):
    return TrackingGate(GateParams(**kw))


def test_good_stream_is_forwarded():
    g = gate()
    for i in range(10):
        assert g.check(i / 30, (i * 0.01, 0, 0), IDQ, COV).ok
    assert g.state == "ok" and g.accepted == 10


@pytest.mark.parametrize("position,quat,cov,state", [
    ((float("nan"), 0, 0), IDQ, COV, "invalid"),
    ((0, 0, 0), (0, 0, float("nan"), 1), COV, "invalid"),
    ((0, 0, 0), IDQ, (0.01, 0.01, float("inf"), 0.01, 0.01, 0.01), "invalid"),
    ((0, 0, 0), (0, 0, 0, 1), (9999.0,) * 6, "lost"),     # RTAB-Map's null pose
    ((0, 0, 0), (0, 0, 0, 0), COV, "lost"),               # zero quaternion
])
def test_bad_poses_are_never_forwarded(position, quat, cov, state):
    g = gate()
    assert g.check(0.0, (0, 0, 0), IDQ, COV).ok
    r = g.check(0.03, position, quat, cov)
    assert (r.ok, r.state, g.state) == (False, state, state)
    assert g.check(0.06, (0, 0, 0), IDQ, COV).ok      # resumes when a good pose comes back
    assert g.state == "ok"


def test_jump_is_rejected_until_reset():
    g = gate(jump_m=0.3, max_speed_mps=1.0)
    assert g.check(0.0, (0, 0, 0), IDQ, COV).ok
    r = g.check(0.033, (1.0, 0, 0), IDQ, COV)
    assert (r.ok, r.state) == (False, "jump") and "jumped 1.000 m" in r.detail
    for i in range(20):   # the new track continues: still rejected (relock_after = 0)
        assert not g.check(0.066 + i / 30, (1.0 + i * 0.001, 0, 0), IDQ, COV).ok
    g.reset()
    assert g.check(1.0, (1.02, 0, 0), IDQ, COV).ok


def test_rotation_jump():
    g = gate(jump_deg=45.0, max_rate_dps=90.0)
    assert g.check(0.0, (0, 0, 0), IDQ, COV).ok
    q = (0, 0, math.sin(math.radians(60)), math.cos(math.radians(60)))   # 120 deg about z
    r = g.check(0.01, (0, 0, 0), q, COV)
    assert (r.ok, r.state) == (False, "jump") and "orientation jumped 120.0 deg" in r.detail


def test_back_on_the_old_track_after_a_jump_is_accepted():
    g = gate()
    assert g.check(0.0, (0, 0, 0), IDQ, COV).ok
    assert not g.check(0.03, (5, 0, 0), IDQ, COV).ok
    assert g.check(0.06, (0.01, 0, 0), IDQ, COV).ok


def test_relock_after_consistent_poses():
    g = gate(relock_after=3)
    assert g.check(0.0, (0, 0, 0), IDQ, COV).ok
    results = [g.check(0.03 * (i + 1), (2.0 + 0.01 * i, 0, 0), IDQ, COV).ok for i in range(5)]
    assert results == [False, False, False, True, True]


def test_gap_allowance_is_capped_at_the_stale_timeout():
    g = gate(jump_m=0.3, max_speed_mps=1.0, stale_timeout_s=0.5)
    assert g.check(0.0, (0, 0, 0), IDQ, COV).ok
    # 10 s later, 0.7 m away: 0.3 + 1.0 * min(10, 0.5) = 0.8 m allowed
    assert g.check(10.0, (0.7, 0, 0), IDQ, COV).ok
    # another 10 s, 0.9 m further: beyond 0.8 m
    assert not g.check(20.0, (1.6, 0, 0), IDQ, COV).ok


def test_stale_stream():
    g = gate(stale_timeout_s=0.5)
    assert g.state_at(0.0)[0] == "waiting"
    g.check(0.0, (0, 0, 0), IDQ, COV)
    assert g.state_at(0.4)[0] == "ok"
    state, detail = g.state_at(0.7)
    assert state == "stale" and "no odometry for 0.70 s" in detail
    assert g.check(0.8, (0, 0, 0), IDQ, COV).ok and g.state_at(0.8)[0] == "ok"


def test_bad_gate_parameters(tmp_path):
    with pytest.raises(ValueError, match="jump_m: must be a positive number, got -1"):
        gate(jump_m=-1)
    f = tmp_path / "c.yaml"
    f.write_text("lost_tracking: {jump_cm: 3}\n")
    with pytest.raises(ValueError, match="lost_tracking.jump_cm: unknown key"):
        load_gate_params(f)


# ---- absurd but finite poses ---------------------------------------------------------------------
def test_a_first_pose_far_outside_the_workspace_is_refused_and_normal_poses_still_pass():
    g = gate(workspace_m=100.0)
    r = g.check(0.0, (1e300, 0, 0), IDQ, COV)
    assert (r.ok, r.state) == (False, "invalid")
    assert "position" in r.detail and "outside the workspace" in r.detail and "workspace_m 100" in r.detail
    r = g.check(0.03, (0.1, 0.0, 0.0), IDQ, COV)   # was refused as "jumped inf m" until reset
    assert r.ok and g.state == "ok"
    assert not g.check(0.06, (0.1, -101.0, 0.0), IDQ, COV).ok   # the bound holds on every axis


def test_a_huge_quaternion_is_not_a_unit_quaternion_and_not_a_zero_one():
    g = gate()
    r = g.check(0.0, (0, 0, 0), (0.0, 0.0, 1e200, 1e200), COV)
    assert (r.ok, r.state) == (False, "invalid")
    assert "not a unit quaternion (norm 1.41421e+200" in r.detail and "zero" not in r.detail
    r = g.check(0.01, (0, 0, 0), (0.0, 0.0, 0.0, 1.05), COV)      # 5 % off: refused too
    assert not r.ok and "not a unit quaternion (norm 1.05" in r.detail
    assert g.check(0.02, (0, 0, 0), (0.0, 0.0, 0.0, 1.005), COV).ok   # within the 1 % tolerance
    r = g.check(0.03, (0, 0, 0), (0.0, 0.0, 0.0, 0.0), COV)
    assert (r.state, "zero quaternion" in r.detail) == ("lost", True)   # RTAB-Map's null pose


@pytest.mark.parametrize("position,quat,cov,field", [
    ((float("nan"), 0, 0), IDQ, COV, "position"),
    ((0, 0, 0), (0, float("inf"), 0, 1), COV, "orientation"),
    ((0, 0, 0), IDQ, (0.01, float("nan"), 0.01, 0.01, 0.01, 0.01), "covariance"),
])
def test_a_non_finite_value_is_blamed_on_its_own_field(position, quat, cov, field):
    r = gate().check(0.0, position, quat, cov)
    assert (r.ok, r.state) == (False, "invalid")
    assert r.detail.startswith(f"non-finite {field} ")
    others = {"position", "orientation", "covariance"} - {field}
    assert not any(o in r.detail for o in others), r.detail


def test_workspace_and_tolerance_come_from_camera_yaml(root, tmp_path):
    p = load_gate_params(root / "config" / "camera.yaml")
    assert (p.workspace_m, p.quaternion_tolerance) == (100.0, 0.01)
    message = refused(load_gate_params, tmp_path, "lost_tracking: {workspace_m: -1, quaternion_tolerance: 2}")
    assert "lost_tracking.workspace_m: must be a positive number, got -1" in message
    assert "lost_tracking.quaternion_tolerance: must be at most 0.5, got 2" in message


def test_calibration_values_have_ranges(tmp_path):
    message = refused(load_camera_calibration, tmp_path,
                      "camera_in_head: {translation_m: [1.0e+300, 0, 0], quaternion_xyzw: [0, 0, 1.0e+200, 1.0e+200]}")
    assert "translation_m: each within +-1 m of the head, got [1e+300, 0.0, 0.0]" in message
    assert "quaternion_xyzw: not a unit quaternion (norm 1.41421e+200)" in message


def test_base_covariance_moves_the_camera_covariance_over_the_lever_arm():
    from snake_autonomy.estimation import base_covariance
    # level camera at yaw 30 deg, base H ahead along the heading: position variance 0.01, rotation 0.04
    yaw = 30 * DEG
    camera = make_transform(rot_z(yaw), [1.0, 2.0, 0.0])
    base_in_camera = translation(H, 0.0, 0.0)
    C = np.diag([0.01, 0.01, 0.01, 0.04, 0.04, 0.04])
    B = base_covariance(C.ravel().tolist(), camera, base_in_camera)
    along = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    across = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
    assert along @ B[:3, :3] @ along == pytest.approx(0.01)                  # a turn moves the base across only
    assert across @ B[:3, :3] @ across == pytest.approx(0.01 + H * H * 0.04)  # yaw variance x lever arm^2
    assert B[2, 2] == pytest.approx(0.01 + H * H * 0.04)                     # pitch lifts the base
    assert B[3:, 3:] == pytest.approx(C[3:, 3:])                             # orientation unchanged
    assert np.allclose(B, B.T) and np.all(np.linalg.eigvalsh(B) > 0)
    # no lever arm: the covariance passes unchanged
    assert base_covariance(C, camera, np.eye(4)) == pytest.approx(C)
