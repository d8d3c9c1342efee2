"""FBSR geometry (planning/fbsr/support.py, chain.py): support polygons, the ZMP's edge distance,
the tail-fixed world, the lying posture's contacts, quasi-static torques, on hand cases."""
import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.planning.fbsr.chain import Chain, lying_posture
from snake_autonomy.planning.fbsr.support import Support, convex_hull, polygon_coords

SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]]   # an interior point is not a vertex


def test_signed_distance_to_the_nearest_edge_inside_and_outside():
    u = Support.of(SQUARE)
    d = u.signed_distance([[0.5, 0.5], [0.9, 0.5], [1.5, 0.5], [2.0, 2.0]])
    np.testing.assert_allclose(d, [0.5, 0.1, -0.5, -np.sqrt(2)], atol=1e-12)
    assert u.contains_point([0.2, 0.3]) and not u.contains_point([1.01, 0.3])


def test_margin_shrinks_and_intersection_is_u_cap_u_prime():
    u = Support.of(SQUARE, margin_m=0.1)
    assert u.polygon.area == pytest.approx(0.8 ** 2)
    u_next = Support.of([[0.5, 0], [2, 0], [2, 1], [0.5, 1]])          # U' overlaps half of U
    both = Support.of(SQUARE, other=u_next)
    assert both.polygon.area == pytest.approx(0.5)
    assert both.contains_point([0.75, 0.5]) and not both.contains_point([0.25, 0.5])


def test_collinear_contacts_span_no_polygon():
    assert convex_hull([[0, 0], [1, 1], [2, 2]]).is_empty
    assert Support.of([[0, 0], [1, 1], [2, 2]]).empty
    assert polygon_coords(convex_hull(SQUARE)) == [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]


@pytest.fixture(scope="module")
def chain(root):
    robot = _core.RobotModel.from_yaml(str(root / "config/robots/unified_snake.yaml"))
    return Chain(robot, lying_posture(robot, 0.0, np.radians(8), np.radians(75), 2))


def test_lying_flat_every_frame_is_a_contact_and_the_tail_sits_at_the_origin(chain):
    pose = chain.pose(chain.q_lying)
    np.testing.assert_allclose(pose.positions[:, 2], chain.radius_m, atol=1e-9)
    assert list(chain.contact_frames) == list(range(chain.num_frames))
    np.testing.assert_allclose(pose.positions[-1], [0, 0, chain.radius_m], atol=1e-9)
    # a base of 5 modules: frames 12..17
    assert len(chain.base_contacts(12)) == 6


def test_active_joints_move_only_the_active_frames_the_base_stays_put(chain):
    q = chain.q_lying.copy()
    q[:12] += np.linspace(0.3, -0.2, 12)
    before, after = chain.pose(chain.q_lying), chain.pose(q)
    np.testing.assert_allclose(after.positions[12:], before.positions[12:], atol=1e-12)
    assert np.abs(after.positions[:12] - before.positions[:12]).max() > 0.05


def test_zmp_is_the_centre_of_gravity_with_each_module_mass_at_its_centre(chain):
    """As the MJCF and the URDF place them: the head module (base + head mass) midway between
    frames 0 and 1, link_i's mass midway between frames i and i + 1."""
    q = chain.q_lying.copy()
    q[0], q[2] = 0.8, -0.4
    pose = chain.pose(q)
    m = chain.masses
    module_kg = np.concatenate([[m[0] + m[1]], m[2:]])
    centres = 0.5 * (pose.positions[:-1] + pose.positions[1:])
    cog = (module_kg[:, None] * centres).sum(axis=0) / module_kg.sum()
    np.testing.assert_allclose(pose.zmp, cog[:2], atol=1e-12)
    np.testing.assert_allclose(chain.positions_com(q)[1], cog, atol=1e-12)


def test_gravity_torque_of_the_horizontal_head_is_its_weight_times_lever(chain):
    """The straight robot: joint 1 (pitch) holds the head module's mass at lever H / 2."""
    q = np.zeros(chain.num_joints)
    pose = chain.pose(q)
    tau = chain.gravity_torques(pose, 2)
    # joint 1 at frame 1: the head module (m0 + m1) at its centre, lever H / 2, about a horizontal axis
    h = chain.robot.head_length_m
    assert abs(tau[0]) == pytest.approx((chain.masses[0] + chain.masses[1]) * 9.81 * h / 2, rel=1e-9)
    # joint 2 is a yaw joint (vertical axis when flat): gravity gives it no torque
    assert abs(tau[1]) < 1e-12


def test_zigzag_offsets_rest_the_body_on_the_face_that_holds_its_centre_of_gravity(root):
    robot = _core.RobotModel.from_yaml(str(root / "config/robots/unified_snake.yaml"))
    q = lying_posture(robot, np.radians(2), np.radians(8), np.radians(75), 2)
    pitch = list(robot.pitch_joints)
    np.testing.assert_allclose(np.degrees(q[pitch[:4]]), [2, -4, 4, -4])   # +e, -2e, +2e, ...
    chain = Chain(robot, q)
    pose = chain.pose(q)
    on_floor = np.isin(np.arange(chain.num_frames), chain.contact_frames)
    assert 3 <= on_floor.sum() < chain.num_frames
    np.testing.assert_allclose(pose.positions[on_floor, 2], chain.radius_m, atol=1e-3)
    assert np.all(pose.positions[~on_floor, 2] > chain.radius_m)
    assert Support.of(chain.contacts_xy).contains_point(pose.zmp)
