"""Issue 13 round 16: a turn in place keeps the side chosen at the stop's first replan
(sampler.turn_keeps_side, planner._free_turn, on in nav.yaml): when that side cannot be swept the
robot backs off instead of turning the other way. Round 15's last COBRA depth contact (world 4 seed
3) came from turns to alternate sides that swung the head both ways next to a cylinder.
sampler.goal_disc (measured, off in nav.yaml): the goal bias aims at the goal's disc."""
import dataclasses

import pytest

from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from test_nav_round12 import free_turn
from test_nav_planning import CFG


def keeps_side(on: bool):
    return dataclasses.replace(CFG.sampler, turn_keeps_side=on)


def test_a_turn_never_takes_the_other_side_when_turn_keeps_side():
    kt = CFG.follower.kappa_turn_per_m
    blocked_left = {-3.0: 0.12, -1.5: 0.1, 0.0: 0.0, 1.5: 0.08, 3.0: 0.0}
    # the stop chose left; left has no room to crawl, right has
    assert free_turn(blocked_left, 0.05, turning=1.0, sampler=keeps_side(False)) == pytest.approx(-kt)
    assert free_turn(blocked_left, 0.05, turning=1.0, sampler=keeps_side(True)) is None
    # the chosen side free: turns to it, whichever the flag
    for on in (False, True):
        assert free_turn(blocked_left, 0.05, turning=-1.0, sampler=keeps_side(on)) == pytest.approx(-kt)


def test_nav_yaml_keeps_the_side_not_the_disc_and_both_are_checked():
    sp = NavConfig.from_yaml().sampler
    assert sp.turn_keeps_side is True and sp.goal_disc is False
    with pytest.raises(NavConfigError, match=r"sampler.goal_disc: must be true or false, got 'yes'"):
        NavConfig.from_dict({"sampler": {"goal_disc": "yes"}})
    with pytest.raises(NavConfigError, match=r"sampler.turn_keeps_side: must be true or false, got 1"):
        NavConfig.from_dict({"sampler": {"turn_keeps_side": 1}})


def test_cobra_world_4_seed_3_backs_off_instead_of_swinging_its_head_back(tmp_path, root):
    """Round 15's committed planner, random world 4 seed 3, depth: at 112 s it turned in place
    right (kappa -1.5), at 122 s left (+1.5), swinging the head ~0.2 m each way beside a cylinder;
    backing off at 132 s base_link touched obstacle_1. Keeping the side, no contact to 150 s (the
    whole run: goal reached, measured in the 20x5 experiment). Both runs to 150 s: round 15's
    planner (turn_keeps_side off) and nav.yaml's."""
    from snake_autonomy.sim.nav_batch import NavRun, NavRunSpec
    from snake_autonomy.sim.nav_experiment import random_corridor
    runs = {}
    for on in (False, True):
        cfg = tmp_path / f"keep_{on}.yaml"
        cfg.write_text(f"base: {root / 'config' / 'nav.yaml'}\n" +
                       ("" if on else "sampler: {turn_keeps_side: false}\n"))
        runs[on] = NavRun(NavRunSpec(random_corridor(4), seed=3, time_limit_s=150.0, nav_config=str(cfg),
                                     keep_frames=False)).run()
    turns = lambda run: [r.reason for r in run.replans if "turn in place (kappa" in r.reason]
    off, on = runs[False], runs[True]
    assert off.metrics["collisions"] > 0, off.metrics
    assert any("+1.50" in t for t in turns(off)) and any("-1.50" in t for t in turns(off)), turns(off)
    assert on.metrics["collisions"] == 0, on.metrics


def test_nowhere_to_back_off_to_a_turn_may_still_take_the_other_side():
    """Keeping the side falls back to backing off; without back_off (follower.back_off false) the
    planner still turns to whichever side it can sweep rather than blindly to the stop's side."""
    from test_nav_round5 import WALL, _walled_planner
    from test_nav_planning import T_GC, drawn_mask
    for back_off in (True, False):
        p = _walled_planner(back_off=back_off, back_off_replans=1)
        p.sampler_params = dataclasses.replace(p.sampler_params, turn_keeps_side=True)
        p.replan(0.0, drawn_mask(discs=[(1.1, 0.35, 0.1)]), T_GC, (-1.2, 0.0, 0.0), None)   # seen on the left
        r = p.replan(10.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (2.0, 0.5))        # the goal on the left
        if back_off:            # the first stop backs off; the second cannot sweep left and backs off again
            assert p.follower.mode == "back_off", r.reason
            r = p.replan(20.0, drawn_mask(**WALL), T_GC, (-0.07, 0.0, 0.0), (2.0, 0.5))
            assert p._turning == 1.0 and "no turn the body can sweep: back off" in r.reason, r.reason
        else:
            assert p.follower.mode == "turn_in_place" and "kappa -1.50" in r.reason, r.reason


def arcs_near_the_goal(goal_disc_radius_m: float):
    """The sampler's own five arcs with the free lengths COBRA's mono run of world 11 seed 1 had at
    162 s, the goal 0.32 m ahead-right (0.12 m from its 0.2 m disc), and a route whose cost to go is
    lower to the left (it went round a phantom on the disc's edge). -> the chosen curvature."""
    from snake_autonomy.planning.rectilinear.sampler import Arc, TrajectorySampler
    from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
    from test_nav_planning import K, T_GC, drawn_mask
    s = TrajectorySampler(PerceptionCollisionChecker(K, T_GC, 0.09),
                          dataclasses.replace(CFG.sampler, goal_disc=True), None)
    free = {-3.0: 0.06, -1.5: 0.10, 0.0: 0.16, 1.5: 0.20, 3.0: 0.20}
    s._head_arcs = lambda ground: [Arc(c, poses, sm, free_m=free[float(c)]) for c, poses, sm in s._arcs]
    route_goes_left = lambda xy: 1.0 - 2.0 * xy[:, 1]
    sel = s.select(drawn_mask(), (0.29, -0.13), cost_to_go=route_goes_left, goal_radius_m=goal_disc_radius_m)
    return sel.arc.curvature_per_m


def test_an_arc_entering_the_goal_disc_wins_over_the_route_round_a_phantom():
    assert arcs_near_the_goal(0.0) == pytest.approx(3.0)       # the goal's centre: the route, left, away
    assert arcs_near_the_goal(0.2) == pytest.approx(0.0)       # the straight arc is in the disc at 0.14 m


def test_the_planner_passes_the_goal_radius_when_goal_disc_is_on():
    """A wall ahead-right, the goal 0.2 m before it: both the straight and the -1.5 /m arc enter its
    disc; with goal_disc they tie at the goal and the straighter is taken, without it the one
    passing nearer the centre."""
    from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
    from snake_autonomy.planning.rectilinear.planner import NavPlanner
    from test_nav_planning import K, T_GC, drawn_mask
    from test_nav_round11 import COBRA
    chosen = {}
    for on in (False, True):
        p = NavPlanner(K, 0.09, dataclasses.replace(CFG.sampler, goal_disc=on),
                       RecedingHorizonFollower(CFG.follower), COBRA)
        r = p.replan(0.0, drawn_mask(boxes=[(0.45, 0.7, -0.6, 0.05)]), T_GC, (0.0, 0.0, 0.0), (0.35, -0.15), 0.2)
        chosen[on] = r.selection.arc.curvature_per_m
    assert chosen == {False: pytest.approx(-1.5), True: pytest.approx(0.0)}
