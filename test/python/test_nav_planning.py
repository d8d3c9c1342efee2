"""Perception-space collision checks, arc sampling and the receding-horizon follower, on drawn
ground masks (planning/rectilinear/)."""
import dataclasses
import math

import numpy as np
import pytest

from nav_scenes import CFG, K, T_GC, drawn_mask
from snake_autonomy.perception.ground_region import grow_from_bottom, traversable
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.follower import (FOLLOW, TURN_IN_PLACE, FollowerParams,
                                                          RecedingHorizonFollower)
from snake_autonomy.planning.rectilinear.sampler import TrajectorySampler
from snake_autonomy.planning.rectilinear.unicycle import arc_poses, predict

HEAD_W = 0.051


@pytest.fixture
def sampler(paper_sampler_params):
    """sampler(head_w, **keys): the paper's sampler (conftest paper_sampler_params) with keys over it."""
    def make(head_w=HEAD_W, **kw):
        return TrajectorySampler(PerceptionCollisionChecker(K, T_GC, head_w),
                                 dataclasses.replace(paper_sampler_params, **kw))
    return make


def test_grow_from_bottom_stops_at_first_obstacle_per_column():
    cells = np.ones((6, 3), bool)
    cells[2, 0] = False           # column 0: blocked at row 2 -> rows 3..5 ground
    cells[5, 2] = False           # column 2: blocked at the bottom -> nothing
    g = grow_from_bottom(cells)
    assert g[:, 0].tolist() == [False, False, False, True, True, True]
    assert g[:, 1].all() and not g[:, 2].any()
    mask = np.ones((80, 120), bool)
    mask[:40, :40] = False
    assert traversable(mask, 40)[0:40, 0:40].sum() == 0 and traversable(mask, 40)[40:, :].all()


def test_open_floor_chooses_the_straight_arc_full_length(sampler):
    sel = sampler().select(drawn_mask())
    assert not sel.no_free_arc
    assert sel.arc.curvature_per_m == 0.0
    assert sel.arc.free_m == pytest.approx(CFG.sampler.horizon_m)
    # the sharpest arcs leave the field of view before the horizon: shorter
    assert max(a.free_m for a in sel.arcs if abs(a.curvature_per_m) == 2.0) < CFG.sampler.horizon_m


def test_obstacle_ahead_left_picks_a_right_arc_that_clears_it(sampler):
    disc = (0.5, 0.06, 0.12)
    sel = sampler().select(drawn_mask(discs=[disc]))
    straight = [a for a in sel.arcs if a.curvature_per_m == 0.0][0]
    assert straight.free_m < 0.39                  # footprint edge meets the disc at x = 0.385
    assert sel.arc.curvature_per_m < 0.0           # right (clockwise)
    assert sel.arc.free_m > straight.free_m + 0.1
    # the chosen free prefix keeps the head's footprint off the disc on the floor
    free = sel.arc.poses[sel.arc.s_m <= sel.arc.free_m]
    assert np.hypot(free[:, 0] - disc[0], free[:, 1] - disc[1]).min() > disc[2] + 0.5 * HEAD_W - 0.01


def test_gap_narrower_than_the_head_blocks_the_straight_arc(sampler):
    # two boxes from 0.3 m on, 40 mm apart, straight ahead
    mask = drawn_mask(boxes=[(0.3, 2.0, 0.02, 0.5), (0.3, 2.0, -0.5, -0.02)])
    wide = [a for a in sampler(0.051).select(mask).arcs if a.curvature_per_m == 0.0][0]
    narrow = [a for a in sampler(0.030).select(mask).arcs if a.curvature_per_m == 0.0][0]
    assert wide.free_m <= 0.3 + 1e-9
    assert narrow.free_m == pytest.approx(CFG.sampler.horizon_m)


def test_wall_everywhere_means_no_free_arc_and_turn_in_place(sampler):
    sel = sampler().select(drawn_mask(boxes=[(0.12, 0.5, -3.0, 3.0)]))
    assert sel.no_free_arc and all(a.free_m < 0.15 for a in sel.arcs)
    f = RecedingHorizonFollower(FollowerParams())
    f.update(0.0, (0.0, 0.0, 0.0))
    f.stop_and_turn(-1)
    cmd = f.update(1.0)
    assert cmd.mode == TURN_IN_PLACE and "no collision-free arc" in cmd.reason and "right" in cmd.reason
    assert f.pose[2] == pytest.approx(0.0)      # prediction: not moved forward while stopped


def test_odd_arc_count_and_symmetric_curvatures(sampler):
    s = sampler(num_arcs=7, max_curvature_per_m=3.0)
    assert s.curvatures.tolist() == pytest.approx([-3, -2, -1, 0, 1, 2, 3])
    with pytest.raises(ValueError, match="num_arcs: must be an odd integer >= 1, got 4"):
        sampler(num_arcs=4)


def test_unicycle_arc_and_prediction_agree():
    c, v, dt = 1.5, 0.02, 10.0
    end = arc_poses(c, v * dt, 0.01)[-1]
    assert predict((0.0, 0.0, 0.0), v, v * c, dt) == pytest.approx(tuple(end), abs=1e-9)
    assert arc_poses(0.0, 1.0, 0.1)[-1] == pytest.approx([1.0, 0.0, 0.0])


def test_follower_feedback_steers_back_to_the_path_and_maps_omega_to_kappa():
    p = FollowerParams(speed_m_s=0.02, omega_per_kappa=0.05, omega_offset_rad_s=0.01, kappa_max_per_m=4.0,
                       lookahead_m=0.06, k_heading=0.5, kappa_rate_per_m_s=0.0)     # the paper's follower
    f = RecedingHorizonFollower(p)
    path = arc_poses(0.0, 1.0, 0.01)                       # straight along +x
    f.set_path(path, 0.0)
    cmd = f.update(0.0, (0.1, 0.03, 0.0))                  # 3 cm left of the path
    assert cmd.mode == FOLLOW and cmd.omega_ff_rad_s == 0.0
    assert cmd.omega_fb_rad_s < 0 and cmd.kappa_per_m < 0  # steer right
    assert math.hypot(cmd.target[0] - 0.1, cmd.target[1] - 0.03) <= 0.06 + 1e-9
    assert cmd.target[0] == pytest.approx(math.sqrt(0.06 ** 2 - 0.03 ** 2) + 0.1, abs=0.011)
    assert p.kappa(p.omega(1.7)) == pytest.approx(1.7)
    assert p.kappa(10.0) == 4.0 and p.kappa(-10.0) == -4.0
    # a curved path: feedforward omega = v c when on the path
    f.set_path(arc_poses(1.0, 1.0, 0.005), 1.0)
    cmd = f.update(1.0, (0.0, 0.0, 0.0))
    assert cmd.omega_ff_rad_s == pytest.approx(0.02)
    assert abs(cmd.omega_fb_rad_s) < 0.02
    # no estimate: the pose is predicted from the last command
    before = f.pose
    f.update(6.0)
    assert f.pose[0] > before[0] + 0.09


def test_margin_shortens_every_free_prefix(sampler):
    mask = drawn_mask(discs=[(0.5, 0.06, 0.12)])
    plain = sampler().select(mask)
    kept = sampler(margin_m=0.1).select(mask)
    for a, b in zip(plain.arcs, kept.arcs):
        assert b.free_m == pytest.approx(max(0.0, a.free_m - 0.1))
