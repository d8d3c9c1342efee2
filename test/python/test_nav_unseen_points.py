"""What the planner's checks make of points the current image does not show (collision_check.py):
floor beyond the commit distance that the view has not reached yet is not an obstacle
(sampler.known_free_m), the near field behind and beside the camera counts as free only as far as the
view shows floor, and earlier views answer for hidden points: an obstacle in one of them wins
(sampler.blocked_wins) unless it is only the shadow behind a face that a newer view shows as floor
(sampler.blocked_wins_depth_m)."""
import dataclasses
import math

import numpy as np
import pytest

from nav_scenes import CFG, COBRA, K, T_GC, drawn_mask, shifted
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker, near_field
from snake_autonomy.planning.rectilinear.config import CameraMount, NavConfig, NavConfigError, T_ground_camera
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from snake_autonomy.planning.rectilinear.sampler import TrajectorySampler


@pytest.fixture
def curved_free(paper_sampler_params):
    """curved_free(known_free_m, mask): each arc's free length, the paper's sampler with known_free_m."""
    def free(known_free_m, mask, width=0.25, c=1.0):
        checker = PerceptionCollisionChecker(K, T_GC, width)
        sp = dataclasses.replace(paper_sampler_params, num_arcs=3, max_curvature_per_m=c, known_free_m=known_free_m)
        return {a.curvature_per_m: a.free_m for a in TrajectorySampler(checker, sp).select(mask).arcs}
    return free


def test_an_arc_leaving_the_view_is_free_beyond_known_free_m_and_cut_without_it(curved_free):
    mask = drawn_mask()                                       # open floor
    strict = curved_free(math.inf, mask)
    relaxed = curved_free(0.3, mask)
    # the paper's rule: the curved arcs' footprint leaves the 55 deg view -> cut there
    assert strict[1.0] < 0.8 and strict[-1.0] < 0.8
    assert strict[0.0] == pytest.approx(CFG.sampler.horizon_m)
    # only what is seen blocks beyond 0.3 m: every arc free to the horizon
    for c in (-1.0, 0.0, 1.0):
        assert relaxed[c] == pytest.approx(CFG.sampler.horizon_m)


def test_an_obstacle_the_image_shows_still_blocks_beyond_known_free_m(curved_free):
    mask = drawn_mask(discs=[(0.7, 0.0, 0.1)])
    relaxed = curved_free(0.35, mask)
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


STEEP = T_ground_camera(CameraMount((0.03, 0.0, 0.0), (0.0, 27.2, 0.0)), 0.022)


def furthest_floor_ahead(T) -> float:
    """How far ahead of the camera (along its heading on the floor) the image's top row meets the floor."""
    fwd = T[:2, 2] / np.linalg.norm(T[:2, 2])
    ray = T[:3, :3] @ np.array([(0.0 - K.cx) / K.fx, (0.0 - K.cy) / K.fy, 1.0])
    assert ray[2] < 0, "the steep camera's top row must still look down"
    return float((-T[2, 3] / ray[2]) * ray[:2] @ fwd)


def test_a_view_never_as_wide_as_the_footprint_does_not_free_every_unseen_point():
    top = furthest_floor_ahead(STEEP)
    assert 0.15 < top < 0.3
    fwd = STEEP[:2, 2] / np.linalg.norm(STEEP[:2, 2])
    nf = near_field(K, STEEP, fwd, 0.15)                # the 12-link robot's 0.3 m footprint
    assert math.isfinite(nf) and nf == pytest.approx(top, abs=0.01)
    # the usual camera is unchanged: its view is 0.3 m wide 0.29 m ahead, before its top row
    assert near_field(K, T_GC, T_GC[:2, 2] / np.linalg.norm(T_GC[:2, 2]), 0.15) == pytest.approx(0.29, abs=0.01)
    c = PerceptionCollisionChecker(K, STEEP, 0.3)
    cam = STEEP[:3, 3]
    beside_far = np.array([[cam[0] + 0.5, cam[1] + 0.6, 0.0]])  # no view shows it: not known to be free
    behind = np.array([[cam[0] - 0.2, cam[1] + 0.1, 0.0]])      # where the robot is: free
    ground = np.ones((K.height, K.width), bool)
    assert not c.point_free(beside_far, ground)[0]
    assert c.point_free(behind, ground)[0]


def test_the_near_field_counts_unseen_floor_beside_and_behind_the_camera_as_free():
    """The near field is 0.5 m ahead of the camera for COBRA's 0.5 m footprint, sideways too: floor
    0.3 m to the side that no view shows counts as free, ahead of and behind the camera (capping it
    was measured and dropped)."""
    beside, behind = np.array([[0.35, 0.3, 0.0]]), np.array([[-0.3, 0.3, 0.0]])
    p = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(CFG.follower), COBRA)
    checker = p._checker(T_GC, np.eye(4), CFG.sampler.obstacle_depth_m)
    assert checker.near_field_m == pytest.approx(0.495, abs=0.01)
    assert [bool(checker.point_free(pt, drawn_mask())[0]) for pt in (beside, behind)] == [True, True]


def test_a_hidden_point_one_earlier_view_shows_as_an_obstacle_is_blocked_with_blocked_wins():
    # a disc 0.6 m ahead of a camera 1 m back (hidden now: behind the camera); one earlier view
    # misses it (the classifier called it ground), the other shows it
    point = np.array([[-0.4, 0.0, 0.0]])
    missed, seen = drawn_mask(), drawn_mask(discs=[(0.6, 0.0, 0.06)])
    now = drawn_mask()
    for blocked_wins, order, free in ((False, (missed, seen), True), (False, (seen, missed), True),
                                      (True, (missed, seen), False), (True, (seen, missed), False)):
        c = PerceptionCollisionChecker(K, T_GC, 0.5, blocked_wins=blocked_wins)
        for ground in order:
            c.add_view(ground, shifted(-1.0), obstacle_depth_m=0.25)
        assert bool(c.point_free(point, now)[0]) == free, (blocked_wins, free)
    # ground in every view that shows it: free either way; shown by none: not known
    c = PerceptionCollisionChecker(K, T_GC, 0.5, blocked_wins=True)
    c.add_view(missed, shifted(-1.0), obstacle_depth_m=0.25)
    assert c.point_free(point, now)[0]
    assert not PerceptionCollisionChecker(K, T_GC, 0.5, blocked_wins=True).point_state(
        np.array([[-3.0, 0.0, 0.0]]), now)[1][0]


def test_the_planner_passes_blocked_wins_to_its_checks_and_a_passed_obstacle_stays_blocked():
    # the robot drove straight along x; 0.5 m back one view showed a disc 0.2 m ahead and 0.3 m to
    # the left of where the robot is now (beside the view now: hidden), an older one (0.8 m back)
    # showed ground there (a classifier's miss): only with blocked_wins do the left arcs avoid it
    def free_lengths(blocked_wins):
        sp = dataclasses.replace(CFG.sampler, blocked_wins=blocked_wins)
        p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower))
        for x, ground in ((-0.8, drawn_mask()), (-0.5, drawn_mask(discs=[(0.7, 0.3, 0.06)]))):
            p.replan(0.0, ground, T_GC, (x, 0.0, 0.0))
        r = p.replan(10.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0))
        return {a.curvature_per_m: a.free_m for a in r.selection.arcs}

    off, on = free_lengths(False), free_lengths(True)
    assert all(f == pytest.approx(1.1) for f in off.values())          # measured: every arc 1.1 m
    assert on[1.5] < 0.3 and on[3.0] < 0.3                            # 0.14 and 0.26 m
    assert on[0.0] == pytest.approx(1.1) and on[-1.5] == pytest.approx(1.1) and on[-3.0] == pytest.approx(1.1)


def test_an_old_views_shadow_yields_to_floor_another_view_shows_its_face_does_not():
    # a view 1 m back shows a disc 0.6 m ahead of it: the disc spans x -0.46..-0.34 in the current
    # frame (hidden now, behind the camera); the floor 0.2 m beyond its face is in its shadow
    face, shadow = np.array([[-0.45, 0.0, 0.0]]), np.array([[-0.26, 0.0, 0.0]])
    seen, floor, now = drawn_mask(discs=[(0.6, 0.0, 0.06)]), drawn_mask(), drawn_mask()

    def free(depth_m, views):
        c = PerceptionCollisionChecker(K, T_GC, 0.5, blocked_wins=True, blocked_wins_depth_m=depth_m)
        for ground, x in views:
            c.add_view(ground, shifted(x), obstacle_depth_m=0.25)
        return [bool(c.point_state(p, now)[0][0]) for p in (face, shadow)]

    both = [(floor, -0.7), (seen, -1.0)]            # a newer view showed floor at both points
    assert free(float("inf"), both) == [False, False]          # no depth limit: any obstacle wins
    assert free(0.1, both) == [False, True]                    # 0.1 m: only the face does
    assert free(0.1, [(seen, -1.0)]) == [False, False]         # no view shows floor there: blocked


def test_the_planner_passes_blocked_wins_depth_m_and_it_is_validated():
    sp = dataclasses.replace(CFG.sampler, blocked_wins_depth_m=0.1)
    p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
    assert p._checker(T_GC, np.eye(4), sp.obstacle_depth_m).blocked_wins_depth_m == pytest.approx(0.1)
    with pytest.raises(NavConfigError, match=r"sampler.blocked_wins_depth_m: must be >= 0, got -1"):
        NavConfig.from_dict({"sampler": {"blocked_wins_depth_m": -1}})
