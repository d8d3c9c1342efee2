"""The body's footprint in the perception-space check (planning/rectilinear/):
the checked width covers the body's swept width (sampler.body_clearance_m), the image judges every
point it shows however near, and points hidden now are looked up in earlier replans' images."""
import dataclasses

import numpy as np
import pytest

from nav_scenes import CFG, K, T_GC, drawn_mask, shifted
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from snake_autonomy.planning.rectilinear.sampler import SamplerParams, TrajectorySampler

HEAD_W = 0.09                          # COBRA's capsule diameter


def planner(**sampler_kw):
    sp = dataclasses.replace(CFG.sampler, **sampler_kw)
    return NavPlanner(K, HEAD_W, sp, RecedingHorizonFollower(CFG.follower))


@pytest.fixture
def straight_free(paper_sampler_params):
    """straight_free(width_m, mask, views): the straight arc's free length, the paper's sampler."""
    def free(width_m, mask, views=()):
        checker = PerceptionCollisionChecker(K, T_GC, width_m)
        for ground, T in views:
            checker.add_view(ground, T)
        sel = TrajectorySampler(checker, dataclasses.replace(paper_sampler_params, num_arcs=1)).select(mask)
        return sel.arcs[0].free_m
    return free


def test_footprint_width_is_the_body_clearance_when_wider_than_the_head_and_margins():
    assert planner(lateral_margin_m=0.08, body_clearance_m=0.0).footprint_width_m == pytest.approx(0.25)
    assert planner(lateral_margin_m=0.08, body_clearance_m=0.25).footprint_width_m == pytest.approx(0.5)
    assert NavConfig.from_yaml().sampler.body_clearance_m >= 0.2        # config/nav.yaml


def test_an_arc_passing_between_the_head_and_the_body_half_width_is_refused(straight_free):
    # a disc whose edge is 0.20 m beside the straight arc: outside the head's footprint (0.045 m +
    # 0.08 m margin = 0.125 m a side), inside the body's swept half-width (0.25 m)
    disc = (0.8, 0.30, 0.10)
    mask = drawn_mask(discs=[disc])
    head = planner(lateral_margin_m=0.08, body_clearance_m=0.0).footprint_width_m
    body = planner(lateral_margin_m=0.08, body_clearance_m=0.25).footprint_width_m
    assert straight_free(head, mask) == pytest.approx(CFG.sampler.horizon_m)   # the old check: free
    blocked = straight_free(body, mask)
    assert blocked < disc[0]                                                  # refused before the disc
    assert blocked > 0.3                                                      # but not at the start


def test_the_wide_footprint_on_open_floor_is_free_to_the_horizon(straight_free):
    # the near field (hidden beside the view) grows with the width, to where the view is that wide
    assert straight_free(0.5, drawn_mask()) == pytest.approx(CFG.sampler.horizon_m)
    c = PerceptionCollisionChecker(K, T_GC, 0.5)
    assert 0.45 < c.near_field_m < 0.55


def test_an_obstacle_the_image_shows_is_not_free_however_near(straight_free):
    # a box straight ahead from 0.15 m: inside the near field of a 0.5 m footprint (0.49 m), shown
    mask = drawn_mask(boxes=[(0.15, 0.5, -0.05, 0.05)])
    c = PerceptionCollisionChecker(K, T_GC, 0.5)
    assert c.near_field_m > 0.4
    assert straight_free(0.5, mask) < 0.15


def test_an_obstacle_beside_the_body_seen_by_an_earlier_view_stays_blocked(straight_free):
    # a disc 0.25 m to the left of the robot now (hidden: beside the view); 0.5 m back, the camera
    # saw it 0.55 m ahead
    disc_now = (0.05, 0.25, 0.08)
    earlier = drawn_mask(discs=[(disc_now[0] + 0.5, disc_now[1], disc_now[2])])
    now = drawn_mask()
    assert straight_free(0.5, now) == pytest.approx(CFG.sampler.horizon_m)    # hidden: near field
    assert straight_free(0.5, now, [(earlier, shifted(-0.5))]) == 0.0          # seen before: blocked
    # floor the earlier view saw as ground stays free
    assert straight_free(0.5, now, [(drawn_mask(), shifted(-0.5))]) == pytest.approx(CFG.sampler.horizon_m)


def test_the_planner_keeps_its_earlier_views():
    p = planner(earlier_views=2)
    pose = (0.0, 0.0, 0.0)
    for i in range(3):
        p.replan(10.0 * i, drawn_mask(), T_GC, pose, (2.0, 0.0))
    assert len(p._views) == 2
    assert planner(earlier_views=0).sampler_params.earlier_views == 0
    assert SamplerParams(earlier_views=-1).validate() == ["earlier_views: must be an integer >= 0, got -1"]
    assert SamplerParams(body_clearance_m=-0.1).validate() == ["body_clearance_m: must be >= 0, got -0.1"]


def test_floor_far_behind_an_obstacle_in_an_earlier_view_is_hidden_not_blocked():
    # 1 m back, the camera saw a thin wall across the view 0.4 m ahead: the floor behind it is not
    # ground in that image; both points are behind the camera now (hidden)
    wall = drawn_mask(boxes=[(0.4, 0.45, -2.0, 2.0)])
    now = drawn_mask()
    shadow = np.array([[-0.2, 0.1, 0.0]])       # 0.8 m ahead of the earlier camera: behind the wall
    on_wall = np.array([[-0.58, 0.1, 0.0]])     # 0.42 m ahead of it: the wall itself
    for depth, shadow_free in ((np.inf, False), (0.25, True)):
        c = PerceptionCollisionChecker(K, T_GC, 0.5)
        c.add_view(wall, shifted(-1.0), obstacle_depth_m=depth)
        assert bool(c.point_free(shadow, now)[0]) == shadow_free
        assert not c.point_free(on_wall, now)[0]
