"""Issue 13 round 10: earlier views disagreeing about a hidden point (sampler.blocked_wins), and the
experiment's time limit (test_nav_experiment.py)."""
import dataclasses

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from test_nav_body_footprint import shifted
from test_nav_planning import CFG, K, T_GC, drawn_mask


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


def test_blocked_wins_is_a_boolean_nav_config_key_on_in_nav_yaml():
    assert NavConfig.from_yaml().sampler.blocked_wins is True
    with pytest.raises(NavConfigError, match=r"blocked_wins: must be true or false, got 'yes'"):
        NavConfig.from_dict({"sampler": {"blocked_wins": "yes"}})
