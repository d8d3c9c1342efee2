"""Algorithm 1 (thesis section 3.7): every row of Table 3.1 and every branch, table-driven.

Geometry used throughout: one waypoint at the origin with heading 0, the robot at (-d, 0), so the
bearing to the waypoint is 0 and, with yaw = -e, both the relative and the absolute yaw errors are e:
the combined error is e whatever the blend weight.
"""
import math

import pytest

from snake_autonomy.control import WaypointTracker

DEG = math.pi / 180.0
FAR = 1.0     # m, > d_th
NEAR = 0.2    # m, <= d_th


def tracker_in(mode=1, delta_deg=0.0, gait=None, waypoints=((0.0, 0.0, 0.0),), **params):
    t = WaypointTracker(list(waypoints), **params)
    t._mode = mode
    t._delta = delta_deg * DEG
    t._gait = gait or {1: "sidewind", 2: "turn_left", 3: "near_turn_left"}[mode]
    return t


def step(t, d, e_deg):
    return t.update(-d, 0.0, -e_deg * DEG)


# (row/branch, distance, mode before, previous delta deg, yaw error deg,
#  -> mode, gait, delta deg after, reached)
CASES = [
    # Table 3.1 row 1 (lines 18-21): FAR, sidewinding, |e| <= 40 deg: steer, delta = 14 + clamp(e, +-7)
    ("row1 small +", FAR, 1, 0.0, 3.0, 1, "sidewind", 17.0, False),
    ("row1 small -", FAR, 1, 0.0, -3.0, 1, "sidewind", 11.0, False),
    ("row1 clamp +", FAR, 1, 0.0, 35.0, 1, "sidewind", 21.0, False),
    ("row1 clamp -", FAR, 1, 0.0, -35.0, 1, "sidewind", 7.0, False),
    ("row1 at +40", FAR, 1, 0.0, 40.0 - 1e-7, 1, "sidewind", 21.0, False),
    # Table 3.1 row 2 (lines 22-27): FAR, sidewinding, |e| > 40 deg: turn in place, delta unchanged
    ("row2 left", FAR, 1, 17.0, 45.0, 2, "turn_left", 17.0, False),
    ("row2 right", FAR, 1, 17.0, -45.0, 2, "turn_right", 17.0, False),
    ("row2 left wide", FAR, 1, 0.0, 170.0, 2, "turn_left", 0.0, False),
    # ERRATA #11: delta of the previous step > +20 deg turns LEFT even though e < -40 deg (line 22)
    ("errata11 prev delta +21", FAR, 1, 21.0, -45.0, 2, "turn_left", 21.0, False),
    # ... and delta < -20 deg (line 25) never overrides line 22 when e > +40 deg
    ("errata11 prev delta -21", FAR, 1, -21.0, 45.0, 2, "turn_left", -21.0, False),
    ("errata11 prev delta -21 right", FAR, 1, -21.0, -45.0, 2, "turn_right", -21.0, False),
    # Table 3.1 row 3 (lines 29-30): FAR, turning, |e| <= 30 deg: back to sidewinding, previous delta
    ("row3 back to sidewind", FAR, 2, 17.0, 25.0, 1, "sidewind", 17.0, False),
    ("row3 back, negative", FAR, 2, 17.0, -25.0, 1, "sidewind", 17.0, False),
    ("row3 keep turning", FAR, 2, 17.0, 35.0, 2, "turn_left", 17.0, False),
    # Literal Algorithm 1: a NEAR turn (mode 3) in the FAR branch is not ended (no branch for it)
    ("far mode 3 literal", FAR, 3, 17.0, 10.0, 3, "near_turn_left", 17.0, False),
    # Table 3.1 row 4 (lines 35-36): NEAR, sidewinding, |e| <= 30 deg: waypoint reached
    ("row4 reached", NEAR, 1, 17.0, 25.0, 1, "stop", 17.0, True),
    ("row4 reached negative", NEAR, 1, 17.0, -25.0, 1, "stop", 17.0, True),
    ("row4 at d_th", 0.35, 1, 17.0, 0.0, 1, "stop", 17.0, True),
    # Table 3.1 row 5 (lines 37-42): NEAR, sidewinding, |e| > 30 deg: NEAR turn to align heading
    ("row5 left", NEAR, 1, 17.0, 35.0, 3, "near_turn_left", 17.0, False),
    ("row5 right", NEAR, 1, 17.0, -35.0, 3, "near_turn_right", 17.0, False),
    # Table 3.1 row 6 (lines 44-45): NEAR, turning, |e| <= 30 deg: switch to sidewind (not reached yet)
    ("row6 aligned", NEAR, 3, 17.0, 25.0, 1, "sidewind", 17.0, False),
    ("row6 keep turning", NEAR, 3, 17.0, -35.0, 3, "near_turn_left", 17.0, False),
    # Literal Algorithm 1: a FAR turn (mode 2) in the NEAR branch keeps turning
    ("near mode 2 literal", NEAR, 2, 17.0, 10.0, 2, "turn_left", 17.0, False),
]


@pytest.mark.parametrize("name,d,mode,prev_delta,e,mode_after,gait,delta_after,reached", CASES,
                         ids=[c[0] for c in CASES])
def test_table_3_1_and_every_branch(name, d, mode, prev_delta, e, mode_after, gait, delta_after, reached):
    t = tracker_in(mode, prev_delta)
    cmd = step(t, d, e)
    assert cmd.mode == mode_after
    assert cmd.gait == gait
    assert cmd.delta_rad == pytest.approx(delta_after * DEG, abs=1e-9)
    assert cmd.reached is reached
    assert cmd.waypoint_index == (1 if reached else 0)
    assert cmd.done is reached
    assert cmd.target_index == 0
    assert cmd.distance == pytest.approx(d)
    assert cmd.yaw_error == pytest.approx(e * DEG, abs=1e-9)
    assert cmd.branch == ("far" if d > 0.35 else "near")
    assert cmd.steer is (gait == "sidewind")


@pytest.mark.parametrize("d,mode,e", [(FAR, 3, 10.0), (NEAR, 2, 10.0)])
def test_turn_exit_any_branch_option(d, mode, e):
    t = tracker_in(mode, 17.0, turn_exit_any_branch=True)
    cmd = step(t, d, e)
    assert (cmd.mode, cmd.gait) == (1, "sidewind")


def test_row6_then_reached_on_the_next_step():
    t = tracker_in(3, 17.0, waypoints=[(0, 0, 0), (5, 0, 0)])
    first = step(t, NEAR, 25.0)
    assert (first.mode, first.reached, first.waypoint_index) == (1, False, 0)
    second = step(t, NEAR, 25.0)
    assert (second.reached, second.waypoint_index, second.target_index, second.done) == (True, 1, 0, False)
    assert second.gait == "sidewind"   # the running gait continues towards the next waypoint


def test_waypoints_advance_to_done_then_stop():
    wps = [(1.0, 0.0, 0.0), (2.0, 0.0, math.pi / 2)]
    t = WaypointTracker(wps)
    a = t.update(1.0, 0.0, 0.0)
    assert (a.reached, a.waypoint_index, a.done, a.gait) == (True, 1, False, "sidewind")
    b = t.update(2.0, 0.1, math.pi / 2)
    assert (b.reached, b.target_index, b.waypoint_index, b.done, b.gait) == (True, 1, 2, True, "stop")
    c = t.update(0.0, 0.0, 0.0)
    assert (c.done, c.waypoint_index, c.gait, c.reached, c.steer) == (True, 2, "stop", False, False)


def test_errors_follow_lines_5_to_8():
    # waypoint (1, 1) heading 90 deg; robot at the origin with yaw 0: rel 45 deg, abs 90 deg
    t = WaypointTracker([(1.0, 1.0, math.pi / 2)])
    cmd = t.update(0.0, 0.0, 0.0)
    d = math.sqrt(2.0)
    w = 0.5 - 0.5 * (3 * ((d - 1) / 0.5) ** 2 - 2 * ((d - 1) / 0.5) ** 3)
    assert cmd.distance == pytest.approx(d)
    assert cmd.yaw_error_rel == pytest.approx(math.pi / 4)
    assert cmd.yaw_error_abs == pytest.approx(math.pi / 2)
    assert cmd.w == pytest.approx(w)
    assert cmd.yaw_error == pytest.approx(w * math.pi / 2 + (1 - w) * math.pi / 4)


@pytest.mark.parametrize("yaw_deg,heading_deg,expected_abs_deg", [
    (-179.0, 179.0, -2.0), (179.0, -179.0, 2.0), (180.0, -180.0, 0.0), (-170.0, 170.0, -20.0)])
def test_absolute_error_wraps_at_180(yaw_deg, heading_deg, expected_abs_deg):
    t = WaypointTracker([(0.0, 0.0, heading_deg * DEG)])
    cmd = t.update(0.1, 0.0, yaw_deg * DEG)
    assert cmd.yaw_error_abs == pytest.approx(expected_abs_deg * DEG, abs=1e-9)


def test_relative_error_wraps_at_180():
    # waypoint behind the robot at bearing 180 deg; yaw -179 deg: relative error -1 deg, not 359 deg
    t = WaypointTracker([(0.0, 0.0, 0.0)])
    cmd = t.update(2.0, 0.0, -179.0 * DEG)
    assert cmd.yaw_error_rel == pytest.approx(-1.0 * DEG, abs=1e-9)
    assert cmd.w == 0.0
    assert (cmd.mode, cmd.gait) == (1, "sidewind")
    assert cmd.delta_rad == pytest.approx(13.0 * DEG)


def test_parameters_from_the_table_are_the_defaults():
    p = WaypointTracker([(0, 0, 0)]).params
    assert (p.d_th, p.kp) == (0.35, 1.0)
    assert [round(v / DEG, 9) for v in (p.psi_wp, p.psi_turn, p.delta0, p.delta_lim, p.delta_turn)] == \
        [30.0, 40.0, 14.0, 7.0, 20.0]


def test_parameters_are_keyword_overrides():
    t = WaypointTracker([(0.0, 0.0, 0.0)], d_th=0.1, psi_turn=50 * DEG, delta0=0.0, delta_lim=5 * DEG, kp=2.0)
    cmd = step(t, 0.2, 45.0)         # FAR now (0.2 > 0.1), 45 < 50: sidewind, delta = clamp(90, +-5)
    assert (cmd.branch, cmd.mode) == ("far", 1)
    assert cmd.delta_rad == pytest.approx(5 * DEG)


def test_bad_configuration_lists_every_problem():
    with pytest.raises(ValueError) as err:
        WaypointTracker([(0, 0, 0), (1, float("nan"), 0), (1, 2)], d_th=-1.0, psi_wp=50 * DEG)
    text = str(err.value)
    assert "d_th: must be positive, got -1.0" in text
    assert "psi_wp: must not exceed psi_turn" in text
    assert "waypoints[1]: every value must be finite" in text
    assert "waypoints[2]: expected (x_m, y_m, heading_rad), got (1, 2)" in text


def test_unknown_parameter_and_empty_waypoints():
    with pytest.raises(ValueError, match=r"psi_wp_deg: unknown tracker parameter \(value 30\)"):
        WaypointTracker([(0, 0, 0)], psi_wp_deg=30)
    with pytest.raises(ValueError, match="at least one waypoint"):
        WaypointTracker([])


def test_non_finite_pose_is_refused():
    t = WaypointTracker([(0, 0, 0)])
    with pytest.raises(ValueError, match="yaw_rad: must be a finite number, got nan"):
        t.update(0.0, 0.0, float("nan"))
    assert t.waypoint_index == 0


def test_closed_loop_unicycle_reaches_every_star_vertex():
    """A crude kinematic plant: sidewinding moves 0.1 m per step along the yaw and turns by
    0.5 (delta - delta0); turns rotate in place by 20 deg per step in the commanded direction. Each
    vertex's heading is the direction of the leg that reaches it. The tracker must visit them all."""
    verts = [(2.0 * math.cos(math.radians(90 + 144 * i)), 2.0 * math.sin(math.radians(90 + 144 * i)))
             for i in range(5)]
    prev = [(0.0, 0.0)] + verts[:-1]
    wps = [(vx, vy, math.atan2(vy - py, vx - px)) for (vx, vy), (px, py) in zip(verts, prev)]
    t = WaypointTracker(wps)
    x = y = yaw = 0.0
    rate = {"turn_left": 20 * DEG, "turn_right": -20 * DEG, "near_turn_left": 20 * DEG,
            "near_turn_right": -20 * DEG}
    reached = []
    for _ in range(400):
        cmd = t.update(x, y, yaw)
        if cmd.reached:
            reached.append(cmd.target_index)
            assert cmd.distance <= 0.35 and abs(cmd.yaw_error) <= 30 * DEG
        if cmd.done:
            break
        if cmd.gait == "sidewind":
            yaw += 0.5 * (cmd.delta_rad - 14 * DEG)
            x += 0.1 * math.cos(yaw)
            y += 0.1 * math.sin(yaw)
        else:
            yaw += rate[cmd.gait]
    assert reached == [0, 1, 2, 3, 4], f"stuck at waypoint {t.waypoint_index} mode {t.mode}"
