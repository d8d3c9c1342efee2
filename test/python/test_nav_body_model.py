"""The body as a curve (body_model.py) and how COBRA's body really moves.

The model: the middle lies half the body back along its curvature; a new curvature swings both ends
to the inside of the turn, (L^2/8) kappa, about the middle or (keep_centroid) about the centroid.

The measurement (runs/gait_map.py simulate_point: the C++ driver's rectilinear gait, nav runs' flat
belly, the centroid of the body's frames over 4 gait cycles, in base_link's frame). The planner's
unicycle says the head moves along its heading and turns at omega_per_kappa * kappa (config/nav.yaml
follower: 0.00923 rad/s per 1/m, a line through 0 fitted over kappa 0..2). Below about 0.4 /m COBRA
does not turn at all: the bent body translates along the tangent of its MIDDLE, which lies
kappa * L/2 to the right of the head's heading for a left bend (L/2 = 0.755 m: 15 deg at 0.35 /m).
`snake_autonomy gait-map --robot cobra --driver-gait rectilinear --amplitudes 0.02 --wavelength 1.0
--kappas 0 0.25 0.35 0.5 0.75 1 2 --flat-belly 0.8 --engine serial --out DIR` (6 s) measured:
omega -0.028 / +0.010 / +0.112 / +0.364 / +0.496 / +1.072 deg/s at kappa 0.25 / 0.35 / 0.5 / 0.75 /
1 / 2 (the line: 0.13 / 0.19 / 0.26 / 0.40 / 0.53 / 1.06); the centroid moving -10.3 / -14.9 / -19.7
/ -28.5 / -37.2 / -66.2 deg off the head's heading against the middle's tangent -10.8 / -15.1 /
-21.6 / -32.4 / -43.3 / -86.5."""
import math

import pytest

from nav_scenes import COBRA, HALF_LENGTH_M
from snake_autonomy.planning.rectilinear import body_model
from snake_autonomy.planning.rectilinear.body_model import BodyGeometry, body_poses
from snake_autonomy.runs.gait_map import gait_map_points, simulate_point


def test_the_middle_is_half_the_body_back_along_its_curvature():
    assert body_model.middle_pose((0.0, 0.0, 0.0), 0.0, 0.75) == pytest.approx((-0.75, 0.0, 0.0))
    x, y, th = body_model.middle_pose((0.0, 0.0, 0.0), 1.0, 0.75)
    assert th == pytest.approx(-0.75)                          # the chord turns by L/2 * kappa
    assert x == pytest.approx(-math.sin(0.75)) and y == pytest.approx(1.0 - math.cos(0.75))


def test_a_new_curvature_swings_the_head_by_l2_over_8_per_unit_of_kappa():
    # measured (bench/nav_body_sweep): 0.28 m per 1/m on COBRA (L 1.51 m)
    mid = body_model.middle_pose((0.0, 0.0, 0.0), 0.0, COBRA.half_length_m)
    shapes = body_model.body_poses(mid, 0.0, 1.0, COBRA.half_length_m, 0.01)
    L = 2.0 * COBRA.half_length_m
    head = shapes[-1][-1]
    assert head[1] == pytest.approx(L * L / 8.0, rel=0.08)
    assert head[2] == pytest.approx(L / 2.0, abs=0.02)         # its heading turns by L/2 kappa
    assert len(shapes) == len(body_model.RESHAPE_FRACTIONS)
    # tail to head, the last shape the new arc: both ends swung to the inside (+y)
    assert shapes[-1][0, 1] > 0.2 and shapes[-1][-1, 1] > 0.2
    assert shapes[0][-1, 1] < shapes[-1][-1, 1]


OMEGA_PER_KAPPA = 0.00923      # config/nav.yaml follower.omega_per_kappa (rad/s per 1/m)


@pytest.fixture(scope="module")
def points():
    pts = gait_map_points("cobra", "rectilinear", [0.02], [0.35, 1.0], wavelength_m=1.0,
                          flat_belly_fraction=0.8, driver_gait="rectilinear")
    return {p.kappa_per_m: simulate_point(p) for p in pts}


def test_half_length_is_cobras():
    from snake_autonomy import _core
    from snake_autonomy.cli.nav import robot_yaml
    body = BodyGeometry.of_robot(_core.RobotModel.from_yaml(str(robot_yaml("cobra"))))
    assert body.half_length_m == pytest.approx(HALF_LENGTH_M, abs=1e-3)


def test_cobra_does_not_turn_below_about_0_4_per_m(points):
    """At 0.35 /m the heading turns less than a tenth of what the follower's line predicts; at 1 /m
    the line holds (within 15 %): a dead band, not a smaller slope."""
    slow, fast = points[0.35]["xi_w_rad_s"], points[1.0]["xi_w_rad_s"]
    assert abs(slow) < 0.1 * OMEGA_PER_KAPPA * 0.35, slow
    assert fast == pytest.approx(OMEGA_PER_KAPPA * 1.0, rel=0.15)


def test_at_a_small_curvature_the_body_moves_along_its_middles_tangent(points):
    """At 0.35 /m (bent left) the centroid moves within 2 deg of the middle's tangent, 15 deg right
    of the head's heading, at nearly the straight gait's speed: the robot side-steps to the right
    of where its head points instead of turning left."""
    p = points[0.35]
    moving = math.degrees(math.atan2(p["xi_y_m_s"], p["xi_x_m_s"]))
    tangent = -math.degrees(0.35 * HALF_LENGTH_M)
    assert moving == pytest.approx(tangent, abs=2.0)
    assert moving < -12.0
    assert math.hypot(p["xi_x_m_s"], p["xi_y_m_s"]) > 0.006


def test_cobra_reshapes_about_its_centroid_not_its_middle():
    """Straight to 1 /m (runs/turn_sweep.py reshape_step, through the C++ driver): measured head +0.172,
    tail +0.197 m to the inside, the frames at the middle -0.063..-0.075 m to the OUTSIDE, the
    centroid +0.029 m. body_model's middle-fixed model says +0.285 at both ends and 0 at the middle;
    keeping the centroid, +0.19 and -0.095. About 4 s."""
    from snake_autonomy.runs.turn_sweep import reshape_step
    r = reshape_step(1.0)
    assert abs(r.centroid_m) < 0.04
    mid = r.lateral_m[len(r.lateral_m) // 2 - 1:len(r.lateral_m) // 2 + 2]
    assert (mid < -0.04).all(), r.lateral_m
    assert 0.1 < r.lateral_m[0] < 0.25 and 0.1 < r.lateral_m[-1] < 0.25, r.lateral_m


def test_the_12_link_robot_reshapes_about_its_centroid_too():
    """The 12-link robot (L 0.84 m), straight to 3 /m in 3 s, then 2.5 s on: measured head +0.180, tail
    +0.117 m to the inside, the frames at the middle -0.058..-0.076 m to the OUTSIDE, the centroid
    +0.018 m. Keeping the centroid, body_poses says +0.18 at the ends and -0.08 at the middle; about the
    middle, +0.26 and 0. About 2 s."""
    from snake_autonomy.runs.turn_sweep import reshape_step
    r = reshape_step(3.0, "chang_rectilinear")
    assert abs(r.centroid_m) < 0.04
    mid = r.lateral_m[len(r.lateral_m) // 2 - 1:len(r.lateral_m) // 2 + 2]
    assert (mid < -0.04).all(), r.lateral_m
    assert 0.08 < r.lateral_m[0] < 0.23 and 0.08 < r.lateral_m[-1] < 0.23, r.lateral_m


def test_body_poses_keeping_the_centroid():
    """The model of the test above (body_model.body_poses keep_centroid): from straight to 1 /m the
    centroid stays, the middle goes (1 - sin(u) / u) / kappa = 0.093 m to the outside (u = 0.755) and
    the ends (1 - cos(u)) / kappa - 0.093 = 0.179 m to the inside; without it the middle stays."""
    middle = (0.0, 0.0, 0.0)
    now = body_poses(middle, 0.0, 0.0, HALF_LENGTH_M, 0.01)[-1]
    kept = body_poses(middle, 0.0, 1.0, HALF_LENGTH_M, 0.01, keep_centroid=True)
    about_middle = body_poses(middle, 0.0, 1.0, HALF_LENGTH_M, 0.01)[-1]
    new = kept[-1]
    assert new[:, :2].mean(axis=0) == pytest.approx(now[:, :2].mean(axis=0), abs=1e-9)
    i = len(new) // 2
    u = HALF_LENGTH_M
    assert new[i, 1] == pytest.approx(-(1 - math.sin(u) / u), abs=2e-3)
    assert new[-1, 1] == pytest.approx((1 - math.cos(u)) - (1 - math.sin(u) / u), abs=2e-3)
    assert about_middle[i, 1] == pytest.approx(0.0, abs=1e-9)
    assert about_middle[-1, 1] == pytest.approx(1 - math.cos(u), abs=2e-3)
    # every intermediate shape keeps it too
    for shape in kept:
        assert shape[:, :2].mean(axis=0) == pytest.approx(now[:, :2].mean(axis=0), abs=1e-9)
