"""Issue 13 round 5 (planning/rectilinear/): what the camera does not show yet is not an obstacle
beyond the commit distance (sampler.known_free_m), backing off along the track when no arc is free
(follower.back_off + gaits.yaml rectilinear_reverse), and the body as a curve (body_model.py)."""
import dataclasses
import math

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear import body_model
from snake_autonomy.planning.rectilinear.body_model import BodyGeometry
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import BACK_OFF, FollowerParams, RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from snake_autonomy.planning.rectilinear.sampler import SamplerParams, TrajectorySampler
from test_nav_planning import CFG, K, T_GC, drawn_mask

COBRA = BodyGeometry(0.5 * (0.1565 + 11 * 0.123), 0.09)


# ---- known_free_m: the view's edge is not an obstacle ---------------------------------------------

def _curved_free(known_free_m, mask, width=0.25, c=1.0):
    checker = PerceptionCollisionChecker(K, T_GC, width)
    sp = SamplerParams(num_arcs=3, max_curvature_per_m=c, known_free_m=known_free_m)
    return {a.curvature_per_m: a.free_m for a in TrajectorySampler(checker, sp).select(mask).arcs}


def test_an_arc_leaving_the_view_is_free_beyond_known_free_m_and_cut_without_it():
    mask = drawn_mask()                                       # open floor
    strict = _curved_free(math.inf, mask)
    relaxed = _curved_free(0.3, mask)
    # the paper's rule: the curved arcs' footprint leaves the 55 deg view -> cut there
    assert strict[1.0] < 0.8 and strict[-1.0] < 0.8
    assert strict[0.0] == pytest.approx(CFG.sampler.horizon_m)
    # only what is seen blocks beyond 0.3 m: every arc free to the horizon
    for c in (-1.0, 0.0, 1.0):
        assert relaxed[c] == pytest.approx(CFG.sampler.horizon_m)


def test_an_obstacle_the_image_shows_still_blocks_beyond_known_free_m():
    mask = drawn_mask(discs=[(0.7, 0.0, 0.1)])
    relaxed = _curved_free(0.35, mask)
    assert relaxed[0.0] <= 0.7 - 0.1 + 1e-9                   # the straight arc stops at the disc
    assert relaxed[0.0] > 0.35


def test_pose_state_tells_blocked_from_unknown():
    checker = PerceptionCollisionChecker(K, T_GC, 0.09)
    mask = drawn_mask(discs=[(0.6, 0.0, 0.1)])
    poses = np.array([[0.3, 0.0, 0.0],       # seen floor
                      [0.6, 0.0, 0.0],       # the disc
                      [1.0, 1.5, 0.0],       # far beside the view: nobody has seen it
                      [-0.2, 0.0, 0.0]])     # behind the camera: where the robot is (near field)
    blocked, unknown = checker.pose_state(poses, mask)
    assert list(blocked) == [False, True, False, False]
    assert list(unknown) == [False, False, True, False]


# ---- backing off -----------------------------------------------------------------------------------

def test_with_back_off_no_free_arc_backs_off_along_the_track_with_kappa_held():
    fp = dataclasses.replace(CFG.follower, back_off=True, kappa_rate_per_m_s=0.0)
    planner = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(fp))
    planner.follower._kappa = 0.4                             # the body's current curvature
    wall = drawn_mask(boxes=[(0.12, 0.6, -1.0, 1.0)])         # a wall right ahead
    r = planner.replan(0.0, wall, T_GC, (0.0, 0.0, 0.0), (2.0, 0.0))
    assert r.path_world is None and "back off" in r.reason
    cmd = planner.command(0.0, (0.0, 0.0, 0.0))
    assert cmd.mode == BACK_OFF and cmd.kappa_per_m == pytest.approx(0.4)
    # the unicycle prediction moves tail first, turning back along the same circle
    cmd = planner.command(10.0, None)
    x, y, th = planner.follower.pose
    assert x < -0.5 * fp.speed_m_s * 10.0
    assert th < 0.0                                          # kappa > 0 backwards: clockwise
    # a free arc again: following
    r = planner.replan(10.0, drawn_mask(), T_GC, (x, y, th), (2.0, 0.0))
    assert r.path_world is not None and planner.command(10.5, (x, y, th)).mode == "follow"


def test_without_back_off_no_free_arc_still_turns_in_place():
    planner = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(dataclasses.replace(CFG.follower,
                                                                                           back_off=False)))
    planner.replan(0.0, drawn_mask(boxes=[(0.12, 0.6, -1.0, 1.0)]), T_GC, (0.0, 0.0, 0.0), (2.0, 0.0))
    assert planner.command(0.0, (0.0, 0.0, 0.0)).mode == "turn_in_place"


def test_the_reverse_gait_is_the_forward_wave_travelling_the_other_way(root):
    import yaml
    gaits = yaml.safe_load((root / "config" / "gaits.yaml").read_text())["gaits"]
    fwd, rev = gaits["rectilinear"], gaits["rectilinear_reverse"]
    assert rev["pitch"]["lag_deg"] == pytest.approx(-fwd["pitch"]["lag_deg"])
    assert rev["pitch"]["amplitude_deg"] == fwd["pitch"]["amplitude_deg"]
    assert rev["frequency_hz"] == fwd["frequency_hz"] and rev["steering"] == "curvature"


def test_boolean_keys_take_true_or_false_only(tmp_path):
    f = tmp_path / "nav.yaml"
    f.write_text("follower: {back_off: 1}\nsampler: {body_model: yes}\n")
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_yaml(str(f))
    assert "follower.back_off: must be true or false, got 1" in str(e.value)
    f.write_text("follower: {back_off: true}\nsampler: {body_model: false}\n")
    cfg = NavConfig.from_yaml(str(f))
    assert cfg.follower.back_off is True and cfg.sampler.body_model is False


# ---- the body as a curve ---------------------------------------------------------------------------

def test_the_middle_is_half_the_body_back_along_its_curvature():
    assert body_model.middle_pose((0.0, 0.0, 0.0), 0.0, 0.75) == pytest.approx((-0.75, 0.0, 0.0))
    x, y, th = body_model.middle_pose((0.0, 0.0, 0.0), 1.0, 0.75)
    assert th == pytest.approx(-0.75)                          # the chord turns by L/2 * kappa
    assert x == pytest.approx(-math.sin(0.75)) and y == pytest.approx(1.0 - math.cos(0.75))


def test_at_the_current_curvature_the_head_path_starts_at_the_head():
    for kappa in (0.0, 0.6, -1.0):
        mid = body_model.middle_pose((0.0, 0.0, 0.0), kappa, COBRA.half_length_m)
        poses, s = body_model.head_path(mid, kappa, COBRA.half_length_m, 1.0, 0.02)
        assert s[0] == pytest.approx(0.0, abs=0.02) and s[-1] == pytest.approx(1.0)
        assert poses[0, :2] == pytest.approx([0.0, 0.0], abs=0.02)


def test_a_new_curvature_swings_the_head_by_l2_over_8_per_unit_of_kappa():
    # round 4's measurement (bench/nav_body_sweep): 0.28 m per 1/m on COBRA (L 1.51 m)
    mid = body_model.middle_pose((0.0, 0.0, 0.0), 0.0, COBRA.half_length_m)
    poses, _ = body_model.head_path(mid, 1.0, COBRA.half_length_m, 0.5, 0.01)
    L = 2.0 * COBRA.half_length_m
    assert poses[0, 1] == pytest.approx(L * L / 8.0, rel=0.08)
    assert poses[0, 2] == pytest.approx(L / 2.0, abs=0.02)     # its heading turns by L/2 kappa
    shapes = body_model.body_poses(mid, 0.0, 1.0, COBRA.half_length_m, 0.02)
    assert len(shapes) == len(body_model.RESHAPE_FRACTIONS)
    # tail to head, the last shape the new arc: both ends swung to the inside (+y)
    assert shapes[-1][0, 1] > 0.2 and shapes[-1][-1, 1] > 0.2
    assert shapes[0][-1, 1] < shapes[-1][-1, 1]


def test_the_body_model_refuses_an_arc_whose_body_would_sweep_a_seen_obstacle():
    # a disc seen in an earlier view beside the tail: turning left swings the tail there (both
    # ends to the inside of the turn); turning right is free
    sp = dataclasses.replace(CFG.sampler, body_model=True, curvature_step_per_m=0.5, max_curvature_per_m=1.0,
                             body_clearance_m=0.0, known_free_m=0.35, earlier_views=5)
    planner = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
    disc = (0.95, 0.3, 0.1)                  # in the view from 2.4 m back: at (-1.45, 0.3), the tail's end
    planner.replan(0.0, drawn_mask(discs=[disc]), T_GC, (-2.4, 0.0, 0.0), None)
    r = planner.replan(10.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0), None)
    by_c = {round(a.curvature_per_m, 2): a for a in r.selection.arcs}
    assert not by_c[0.5].body_free and by_c[0.5].free_m == 0.0
    assert by_c[-0.5].body_free and by_c[-0.5].free_m > 0.0
    assert NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA).footprint_width_m == \
        pytest.approx(0.09 + 2 * sp.lateral_margin_m)
    with pytest.raises(ValueError, match="body geometry"):
        NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower))


def test_curvature_candidates_stay_within_the_step_and_the_range():
    sp = SamplerParams(num_arcs=5, max_curvature_per_m=1.0, curvature_step_per_m=0.5)
    s = TrajectorySampler(PerceptionCollisionChecker(K, T_GC, 0.25), sp)
    assert list(s.curvatures_around(0.0)) == pytest.approx([-0.5, -0.25, 0.0, 0.25, 0.5])
    assert list(s.curvatures_around(0.8)) == pytest.approx([0.3, 0.55, 0.8, 1.0])
    fixed = TrajectorySampler(PerceptionCollisionChecker(K, T_GC, 0.25), SamplerParams(num_arcs=5))
    assert list(fixed.curvatures_around(0.8)) == pytest.approx([-2.0, -1.0, 0.0, 1.0, 2.0])


def test_after_no_free_arc_the_robot_resumes_only_with_resume_free_m_ahead():
    # arcs to 2 /m (round 6's range): round 7's 3 /m arcs (0.33 m radius) curl round before the wall
    sp = dataclasses.replace(CFG.sampler, resume_free_m=0.6, known_free_m=0.3, body_clearance_m=0.0,
                             max_curvature_per_m=2.0)
    fp = dataclasses.replace(CFG.follower, back_off=True)
    planner = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(fp))
    near = drawn_mask(boxes=[(0.12, 0.6, -1.0, 1.0)])          # a wall 0.12 m ahead: nothing free
    assert planner.replan(0.0, near, T_GC, (0.0, 0.0, 0.0), None).path_world is None
    mid = drawn_mask(boxes=[(0.55, 0.9, -1.0, 1.0)])           # backed off: 0.55 m, free ~0.35 m
    r = planner.replan(10.0, mid, T_GC, (0.0, 0.0, 0.0), None)
    assert max(a.free_m for a in r.selection.arcs) >= sp.min_free_m
    assert r.path_world is None                                 # not enough to resume: back on
    far = drawn_mask(boxes=[(1.0, 1.2, -1.0, 1.0)])
    assert planner.replan(20.0, far, T_GC, (0.0, 0.0, 0.0), None).path_world is not None
    # once following, min_free_m is enough again
    assert planner.replan(30.0, mid, T_GC, (0.0, 0.0, 0.0), None).path_world is not None


def _walled_planner(**follower_kw):
    fp = dataclasses.replace(CFG.follower, kappa_rate_per_m_s=0.0, **follower_kw)
    # the sweep alone: the wall is nearer than a turn's crawl (round 12's turn_free_m, test_nav_round12)
    # round 5's rule: the other side when the turning side cannot be swept (round 16's turn_keeps_side off)
    # and round 5's reshaping about the middle (round 20's centroid moves the ends a third less: test_nav_round20)
    sp = dataclasses.replace(CFG.sampler, turn_free_m=0.0, turn_keeps_side=False, reshape_keeps_centroid=False)
    return NavPlanner(K, 0.09, sp, RecedingHorizonFollower(fp), COBRA)


WALL = dict(boxes=[(0.12, 0.6, -1.0, 1.0)])                    # right ahead: no arc is free


def test_a_turn_in_place_whose_sweep_hits_a_seen_obstacle_is_not_taken():
    # a disc seen 1.1 m ahead of an earlier pose, now beside the head on the left (y 0.35): bending
    # left swings the head (L^2/8) kappa to the left into it (0.21 m at 0.75 /m, 0.43 m at 1.5 /m)
    p = _walled_planner(back_off=False)
    p.replan(0.0, drawn_mask(discs=[(1.1, 0.35, 0.1)]), T_GC, (-1.2, 0.0, 0.0), None)
    r = p.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (2.0, 0.5))   # the goal on the left
    assert r.path_world is None
    assert p.follower.mode == "turn_in_place" and p.follower.turn_direction == -1.0, r.reason
    assert "kappa -1.50" in r.reason
    # without the disc the goal's side is taken
    q = _walled_planner(back_off=False)
    r = q.replan(0.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (2.0, 0.5))
    assert q.follower.turn_direction == 1.0 and "kappa +1.50" in r.reason


def test_with_no_turn_the_body_can_sweep_the_robot_backs_off_again():
    p = _walled_planner(back_off=True, back_off_replans=1)
    discs = [(1.1, 0.35, 0.1), (1.1, -0.35, 0.1)]             # beside the head on both sides
    p.replan(0.0, drawn_mask(discs=discs), T_GC, (-1.2, 0.0, 0.0), None)
    r1 = p.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), None)
    assert "back off" in r1.reason and p.follower.mode == BACK_OFF           # the first stop backs off
    r2 = p.replan(20.0, drawn_mask(**WALL), T_GC, (-0.07, 0.0, 0.0), None)
    assert "no turn the body can sweep" in r2.reason and p.follower.mode == BACK_OFF
    # one side free: the second stop turns there
    q = _walled_planner(back_off=True, back_off_replans=1)
    q.replan(0.0, drawn_mask(discs=discs[:1]), T_GC, (-1.2, 0.0, 0.0), None)
    q.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), None)
    r = q.replan(20.0, drawn_mask(**WALL), T_GC, (-0.07, 0.0, 0.0), None)
    assert q.follower.mode == "turn_in_place" and q.follower.turn_direction == -1.0, r.reason
