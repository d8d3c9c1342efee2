"""Issue 13 round 11: the swing guard (sampler.swing_guard_m, planner.py _swing_bounds): while
following, the body bends only as far as its front can swing without meeting an obstacle the views
show; and the follower's curvature bounds."""
import dataclasses
import math

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear.body_model import BodyGeometry
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from test_nav_planning import CFG, K, T_GC, drawn_mask

COBRA = BodyGeometry(half_length_m=0.755, width_m=0.09)       # BodyGeometry.of_robot(cobra): 1.51 m, 90 mm


def guarded_replan(discs, swing_guard_m=0.2, swing_obstacle_depth_m=0.1):
    """The robot drove straight along x to (0, 0, 0); 0.8 m back its camera saw `discs` (x, y, r in
    that view's ground frame); now it sees open floor. Returns (the replan, the follower)."""
    sp = dataclasses.replace(CFG.sampler, swing_guard_m=swing_guard_m,
                             swing_obstacle_depth_m=swing_obstacle_depth_m,
                             reshape_keeps_centroid=False, swing_guard_tail_m=0.0)   # round 11's body model
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


def test_swing_guard_keys_are_checked_and_on_in_nav_yaml():
    sp = NavConfig.from_yaml().sampler
    assert sp.swing_guard_m == pytest.approx(0.2) and sp.swing_obstacle_depth_m == pytest.approx(0.1)
    with pytest.raises(NavConfigError, match=r"swing_guard_m: must be >= 0, got -0.1"):
        NavConfig.from_dict({"sampler": {"swing_guard_m": -0.1}})
    with pytest.raises(NavConfigError, match=r"swing_obstacle_depth_m: must be > 0, got 0"):
        NavConfig.from_dict({"sampler": {"swing_obstacle_depth_m": 0}})


def test_cobra_passes_the_three_cylinders_of_world_6_without_its_front_links_touching(tmp_path, root):
    """Round 10's committed planner: random world 6 seed 4, depth: reached at 449 s with 21 contact
    episodes (the head passed the right cylinder 0.18 m off, the left arc back to the goal swung
    link 1 into it). With the swing guard: reached without a contact (measured 470 s). ~30 s wall.
    Without round 15's map and route (with them this run ends stopped in the funnel, no contact), and
    with round 19's blocked_wins_depth_m and back_off_check_m at their round-18 values (with them it
    runs to the time limit, no contact), and round 11's body model (with round 20's option
    reshape_keeps_centroid it reached with 6 contact episodes; without the map the tail guard does
    nothing)."""
    from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
    from snake_autonomy.runs.nav_experiment import random_corridor
    world = random_corridor(6)
    cfg = tmp_path / "no_map.yaml"
    cfg.write_text(f"base: {root / 'config' / 'nav.yaml'}\nmap: {{source: none, route: false}}\n"
                   "sampler: {blocked_wins_depth_m: .inf, back_off_check_m: 0.0, reshape_keeps_centroid: false,"
                   " swing_guard_tail_m: 0.0}\n")   # round 18's
    m = NavRun(NavRunSpec(world, seed=4, time_limit_s=567.0, keep_frames=False, nav_config=str(cfg))).run().metrics
    print({k: m[k] for k in ("goal_reached", "time_s", "collisions", "min_clearance_m", "outcome")})
    assert m["goal_reached"] and m["collisions"] == 0, m["outcome"]
