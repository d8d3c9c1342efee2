"""The layered planner's recoveries by behaviour: backing off (steering against the turn, or along the
body's own track), and dead ends (an escape backing off replan after replan; the route's marks)."""
import dataclasses

import numpy as np
import pytest

from nav_scenes import CFG, COBRA, K, T_GC, WALL, drawn_mask
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import BACK_OFF, FOLLOW, RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.grid_route import GridRoute
from snake_autonomy.planning.rectilinear.layered_planner import LayeredPlanner
from snake_autonomy.planning.rectilinear.local_map import LocalMap, LocalMapParams

LAYERED = dataclasses.replace(CFG, planner=dataclasses.replace(CFG.planner, kind="layered"),
                              sampler=dataclasses.replace(CFG.sampler, num_arcs=9))


def layered(kappa=0.0, cfg=LAYERED):
    f = RecedingHorizonFollower(dataclasses.replace(cfg.follower, kappa_rate_per_m_s=0.0))
    f._kappa = kappa
    return LayeredPlanner(K, 0.09, cfg, f, COBRA)


def _know_round(pl, centre, radius_m):
    """The floor within radius_m of centre (world) known: lain on."""
    g = np.mgrid[-radius_m:radius_m:0.02, -radius_m:radius_m:0.02].reshape(2, -1).T
    pl.map.mark_body(g[np.hypot(*g.T) <= radius_m] + centre, 0.02)


STEERING = dataclasses.replace(LAYERED, recovery=dataclasses.replace(LAYERED.recovery, back_off_steer=True))


def _backing_off_from_a_wall(known_round_m, cfg=STEERING):
    """COBRA bent to turn left (kappa_turn_per_m) before a wall; the floor within known_round_m of
    the body's middle known (lain on), beside the start's own."""
    k = cfg.follower.kappa_turn_per_m
    pl = layered(kappa=k, cfg=cfg)
    pl.replan(0.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0))        # places the map, the start's floor known
    _know_round(pl, [-0.75, 0.0], known_round_m)
    pl.recovery.side = 1.0                                     # the route's side: left
    r = pl.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2)
    assert pl.follower.mode == BACK_OFF
    return r, pl.follower.update(10.0, (0.0, 0.0, 0.0)), k


def test_layered_planner_backs_off_steering_against_its_turn_where_the_floor_round_it_is_known():
    r, cmd, k = _backing_off_from_a_wall(1.5)
    assert "steering" in r.reason
    assert cmd.kappa_per_m == pytest.approx(-k)                # backing, the body turns on to the left
    r, cmd, k = _backing_off_from_a_wall(0.0)                  # only the start's floor known
    assert "along the track" in r.reason
    assert cmd.kappa_per_m == pytest.approx(k)                 # the curvature held: its own track
    r, cmd, k = _backing_off_from_a_wall(1.5, LAYERED)         # back_off_steer off (nav.yaml)
    assert "along the track" in r.reason and cmd.kappa_per_m == pytest.approx(k)


def test_the_recovery_keys_are_validated_and_on_for_the_12_link_robot_only(root):
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_dict({"recovery": {"back_off_steer": "yes", "escape_after": 1.5, "escape_m": 0},
                             "critics": {"route_dead_end_cost": -1}})
    for key in ("recovery.back_off_steer", "recovery.escape_after", "recovery.escape_m",
                "critics.route_dead_end_cost"):
        assert key in str(e.value)
    cobra, chang = NavConfig.from_yaml(), NavConfig.from_yaml(root / "config" / "nav_chang_rectilinear.yaml")
    assert not cobra.recovery.back_off_steer and cobra.recovery.escape_after == 0
    assert cobra.critics.route_dead_end_cost == 0.0
    assert chang.recovery.back_off_steer and chang.recovery.escape_after == 4
    assert chang.critics.route_dead_end_cost > 0


def _wall_with_two_gaps():
    m = LocalMap(LocalMapParams(size_m=4.0))
    m._place((0.0, 0.0))
    gaps = ((0.5, 0.2), (-0.9, 0.2))                  # (y, half width): the near one first
    ys = [y for y in np.arange(-2.0, 2.0, 0.02) if all(abs(y - c) > h for c, h in gaps)]
    i, j, _ = m.cells(np.array([[1.0, y] for y in ys]))
    m.log_odds[i, j] = 3.0
    return m


def _crossing(route):
    return route.path[np.argmin(np.abs(route.path[:, 0] - 1.0))][1]


def test_the_route_leaves_a_gap_marked_as_a_dead_end_for_the_other_one():
    m = _wall_with_two_gaps()
    r = GridRoute(0.08, 0.12, 0.045, mark_cost=2.0, mark_radius_m=0.3)
    r.update(m, (0.0, 0.0), (2.0, 0.0))
    assert _crossing(r) == pytest.approx(0.5, abs=0.15)
    for _ in range(4):
        r.mark((1.0, 0.5))                                         # the robot recovered there 4 times
    r.update(m, (0.0, 0.0), (2.0, 0.0))
    assert _crossing(r) == pytest.approx(-0.9, abs=0.15)           # the other gap, 0.45 m longer
    assert r.marks_near((1.1, 0.5)) == 4 and r.marks_near((1.0, -0.9)) == 0
    unmarked = GridRoute(0.08, 0.12, 0.045)
    unmarked.mark((1.0, 0.5))
    unmarked.update(m, (0.0, 0.0), (2.0, 0.0))
    assert _crossing(unmarked) == pytest.approx(0.5, abs=0.15)     # mark_cost 0: marks cost nothing


def test_each_route_cell_costs_its_count_of_marks_within_the_radius_however_far_the_marks_lie():
    m = _wall_with_two_gaps()
    r = GridRoute(0.08, 0.12, 0.045, mark_cost=1.0, mark_radius_m=0.3)
    r.update(m, (0.0, 0.0), (2.0, 0.0))
    rng = np.random.default_rng(3)
    lo, hi = r._lo, r._lo + r._cell * (np.array(r._shape) - 1)
    marks = rng.uniform(lo - 1.0, hi + 1.0, size=(60, 2))        # some outside the window
    marks[:5] = lo + r._cell * np.array([[0, 0], [3, 3], [3, 3], [7.5, 2.0], [0.0, 3.75]])  # on cells, between
    r.marks = marks
    x = lo[0] + r._cell * np.arange(r._shape[0])
    y = lo[1] + r._cell * np.arange(r._shape[1])
    brute = (np.hypot(x[:, None, None] - marks[None, None, :, 0], y[None, :, None] - marks[None, None, :, 1])
             <= 0.3).sum(axis=2)
    assert brute.max() >= 2 and np.array_equal(r._mark_counts(r._shape, r._cell), brute)


def test_a_dead_end_makes_the_robot_back_off_replan_after_replan_until_it_is_out():
    cfg = dataclasses.replace(LAYERED, recovery=dataclasses.replace(LAYERED.recovery, escape_after=3,
                                                                    escape_m=0.3, dead_end_radius_m=0.2))
    pl = layered(cfg=cfg)
    pl.replan(0.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0))
    _know_round(pl, [-0.75, 0.0], 1.5)
    reasons = [pl.replan(10.0 * k, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2).reason
               for k in range(1, 4)]
    assert not any("dead end" in r for r in reasons[:2]) and "dead end" in reasons[2]
    # backing out, arcs ahead are free again: it goes on backing off until 0.3 m from the dead end
    r = pl.replan(40.0, drawn_mask(), T_GC, (-0.2, 0.0, 0.0), (1.5, 0.0), 0.2)
    assert "dead end" in r.reason and pl.follower.mode == BACK_OFF and r.path_world is None
    r = pl.replan(50.0, drawn_mask(), T_GC, (-0.35, 0.0, 0.0), (1.5, 0.0), 0.2)
    # out: planned as ever (here a tight arc away from the wall it remembers)
    assert r.reason.startswith("arc c") and pl.follower.mode == FOLLOW and r.path_world is not None
    assert pl.route.marks_near((0.0, 0.0)) == 3
