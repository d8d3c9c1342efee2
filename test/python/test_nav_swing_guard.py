"""The swing guard (sampler.swing_guard_m and its tail and body parts, planner._swing_bounds): while
following, the body bends only as far as it can swing without meeting an obstacle: its front links
against what the views show, its tail (swing_guard_tail_m) and its middle (swing_guard_body) against
the obstacle map; and the follower keeps its curvature within the bounds it is given."""
import dataclasses

import numpy as np
import pytest
from shapely.geometry import Point

from nav_scenes import CFG, COBRA, HALF_LENGTH_M, K, T_GC, drawn_mask, planner_with, swing_bounds
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.planner import NavPlanner


def guarded_replan(discs, swing_guard_m=0.2, swing_obstacle_depth_m=0.1):
    """The robot drove straight along x to (0, 0, 0); 0.8 m back its camera saw `discs` (x, y, r in
    that view's ground frame); now it sees open floor. Returns (the replan, the follower)."""
    sp = dataclasses.replace(CFG.sampler, swing_guard_m=swing_guard_m,
                             swing_obstacle_depth_m=swing_obstacle_depth_m,
                             reshape_keeps_centroid=False, swing_guard_tail_m=0.0)   # the front guard alone
    follower = RecedingHorizonFollower(CFG.follower)
    p = NavPlanner(K, 0.09, sp, follower, COBRA)
    p.replan(0.0, drawn_mask(discs=discs), T_GC, (-0.8, 0.0, 0.0))
    return p.replan(10.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0)), follower


def test_the_swing_guard_bounds_the_curvature_towards_an_obstacle_beside_the_front_links():
    kmax = CFG.follower.kappa_max_per_m
    # a 5 cm disc 0.15 m behind the head and 0.2 m to its left (link 1's side; seen 0.8 m back)
    r, f = guarded_replan([(0.65, 0.2, 0.05)])
    lo, hi = f._bounds
    assert lo == pytest.approx(-kmax) and hi < 0.3, (lo, hi)           # measured: 0.0
    assert "(swing guard)" in r.reason and f"{hi:+.2f} /m" in r.reason
    # mirrored: the right turn is bounded, the left one free
    _, f = guarded_replan([(0.65, -0.2, 0.05)])
    assert f._bounds[1] == pytest.approx(kmax) and f._bounds[0] > -0.3
    # nothing beside the body, or the guard off: the gait's range / no bounds
    _, f = guarded_replan([])
    assert f._bounds == pytest.approx((-kmax, kmax))
    _, f = guarded_replan([(0.65, 0.2, 0.05)], swing_guard_m=0.0)
    assert f._bounds is None
    # the disc 0.6 m behind the head: beyond the guarded 0.2 m of the body
    _, f = guarded_replan([(0.2, 0.2, 0.05)])
    assert f._bounds == pytest.approx((-kmax, kmax))


def test_the_guard_takes_obstacles_as_their_face_not_the_shadow_behind_them():
    # a disc 0.35 m behind the head, 0.2 m left: its far side is 0.3 m behind, beyond the guarded
    # 0.2 m; the 0.25 m the planner's checks block beyond its near edge reach the front links' lead
    # points, swing_obstacle_depth_m 0.1 (its face) does not
    disc = [(0.45, 0.2, 0.05)]
    _, f_face = guarded_replan(disc)
    _, f_shadow = guarded_replan(disc, swing_obstacle_depth_m=0.25)
    assert f_face._bounds[1] == pytest.approx(CFG.follower.kappa_max_per_m)
    assert f_shadow._bounds[1] < f_face._bounds[1] - 0.5, (f_shadow._bounds, f_face._bounds)   # 0.25 vs 2


def test_the_follower_clips_kappa_to_the_bounds_of_its_path():
    # a tight left arc from the origin: the follower asks for kappa well above 0.3 without bounds
    s = np.linspace(0.0, 0.5, 26)
    c = 3.0
    path = np.column_stack([np.sin(c * s) / c, (1 - np.cos(c * s)) / c, c * s])
    kappas = {}
    for bounds in (None, (-2.0, 0.3)):
        f = RecedingHorizonFollower(dataclasses.replace(CFG.follower, kappa_rate_per_m_s=0.0))
        f.set_path(path, c, bounds)
        kappas[bounds] = f.update(0.0, (0.0, 0.0, 0.0)).kappa_per_m
    assert kappas[None] > 1.0 and kappas[(-2.0, 0.3)] == pytest.approx(0.3)
    with pytest.raises(ValueError, match=r"kappa_bounds: expected lo <= hi, got \(1.0, -1.0\)"):
        RecedingHorizonFollower(CFG.follower).set_path(path, c, (1.0, -1.0))


def test_the_tail_guard_keeps_the_tails_swing_off_what_the_map_holds():
    """The tail guard (sampler.swing_guard_tail_m): bending to kappa swings the tail (L^2/8) kappa
    to the inside of the turn, as far as the head (body_model.py); the swing guard watched only the
    body's first 0.2 m. The 12-link robot's tail touched the cylinder it had passed 0.7 m earlier
    while the head turned left (depth world 4 seed 7). A cylinder in the map 0.25-0.45 m to the left
    of COBRA's straight tail: bending left is bounded, bending right is not."""
    def bounds(tail_m, obstacle=(-1.45, 0.35, 0.1)):
        # reshaping about the middle
        sp = dataclasses.replace(CFG.sampler, swing_guard_tail_m=tail_m, reshape_keeps_centroid=False)
        p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
        p.obstacle_map = ObstacleMap(Point(obstacle[:2]).buffer(obstacle[2], 32))
        return p._swing_bounds(p._checker(T_GC, np.eye(4), sp.swing_obstacle_depth_m), drawn_mask())

    kmax = CFG.follower.kappa_max_per_m
    assert bounds(0.0) == pytest.approx((-kmax, kmax))
    lo, hi = bounds(0.2)
    assert lo == pytest.approx(-kmax) and hi == pytest.approx(0.25)   # 0.285 m per 1/m + 0.125 m reach
    # the same cylinder beside the middle (which does not swing) bounds nothing
    assert bounds(0.2, (-0.75, 0.2, 0.05)) == pytest.approx((-kmax, kmax))


def test_with_the_centroid_kept_the_map_guard_covers_the_middle():
    """Reshaping about the centroid moves the middle (1 - sin(u)/u)/kappa ~ 0.095 m per 1/m to the
    outside of the bend; the swing guard watched the front 0.2 m (views) and the last
    swing_guard_tail_m (map). COBRA depth world 3 seed 0 (centroid, tail 0.2 m): link 5 swung onto
    the cylinder it was passing when the body bent away from it. A disc in the map 0.15 m left of
    the straight body's middle: bending right (its outside is the left) is bounded at -0.25 /m
    (0.024 m + the 0.125 m reach clears it, -0.5 /m's 0.047 m does not) with swing_guard_tail_m 1.5 m
    (the whole body behind the front; measured on 100 runs, not kept); with 0.2 m or
    with the middle kept it is not."""
    def bounds(keep, tail_m):
        return swing_bounds(planner_with((-HALF_LENGTH_M, 0.2, 0.05), 0.0, guard_m=0.0, keep_centroid=keep,
                                         tail_m=tail_m))

    kmax = CFG.follower.kappa_max_per_m
    assert bounds(True, 1.5) == pytest.approx((-0.25, kmax))
    assert bounds(True, 0.2) == pytest.approx((-kmax, kmax))
    assert bounds(False, 1.5) == pytest.approx((-kmax, kmax))


def body_guarded(obstacle, kappa_per_m, on=True):
    """The swing guard's bounds with the centroid kept, the tail guard 0.2 m and the body guard."""
    p = planner_with(obstacle, kappa_per_m, guard_m=0.0, keep_centroid=True, tail_m=0.2, swing_guard_body=on)
    return swing_bounds(p, np.eye(4))


def test_the_body_guard_keeps_the_middle_off_the_map():
    """The body guard (sampler.swing_guard_body): the stations between the front and the tail guard keep
    their distance to the map's obstacles: at least the crawl guard's clearance (half the body's
    0.09 m + crawl_margin_m 0.02 = 0.065 m), or what they have now. Reshaping about the centroid moves
    the middle (1 - sin(u)/u)/kappa to the outside (u = 0.755 kappa). The disc of the test above,
    0.15 m left of the middle: bending right is bounded at -0.75 /m (the middle 0.070 m to the left
    keeps 0.080 m; at -1 /m 0.092 m, leaving 0.058); the guard off, it is not."""
    kmax = CFG.follower.kappa_max_per_m
    assert body_guarded((-HALF_LENGTH_M, 0.2, 0.05), 0.0) == pytest.approx((-0.75, kmax))
    assert body_guarded((-HALF_LENGTH_M, 0.2, 0.05), 0.0, on=False) == pytest.approx((-kmax, kmax))
    # 0.1 m off: -0.25 /m keeps 0.076 m, -0.5 /m 0.053 m
    assert body_guarded((-HALF_LENGTH_M, 0.15, 0.05), 0.0) == pytest.approx((-0.25, kmax))
    # 0.07 m off: -0.25 /m would leave 0.046 m; it may not come nearer, it may go away
    assert body_guarded((-HALF_LENGTH_M, 0.12, 0.05), 0.0) == pytest.approx((0.0, kmax))
    # mirrored: a disc on the right bounds bending left
    assert body_guarded((-HALF_LENGTH_M, -0.15, 0.05), 0.0) == pytest.approx((-kmax, 0.25))


def test_the_body_guard_needs_the_world_frame_and_is_validated():
    p = planner_with((-HALF_LENGTH_M, 0.15, 0.05), 0.0, guard_m=0.0, keep_centroid=True, tail_m=0.2,
                     swing_guard_body=True)
    assert swing_bounds(p) == pytest.approx((-CFG.follower.kappa_max_per_m, CFG.follower.kappa_max_per_m))
    with pytest.raises(NavConfigError, match=r"sampler.swing_guard_body: must be true or false, got 1"):
        NavConfig.from_dict({"sampler": {"swing_guard_body": 1}})
