"""The route and the goal bias (route.py, sampler.py): a route on the obstacle map gives the goal
bias a cost to go, so the robot keeps out of funnels narrower than its checked footprint; an arc
entering the goal's disc wins over the route (sampler.goal_disc), among such arcs the one passing
nearest the centre, and an arc counts as long enough only within goal_tie_m of the longest or free
as far as the goal's centre."""
import dataclasses
import math

import numpy as np
import pytest

from nav_scenes import CFG, COBRA, K, T_GC, drawn_mask
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from snake_autonomy.planning.rectilinear.route import Route
from snake_autonomy.planning.rectilinear.sampler import Arc, TrajectorySampler
from snake_autonomy.runs.nav_experiment import random_corridor


def test_the_route_goes_round_world_6s_funnel_not_through_it():
    world = random_corridor(6)                       # three cylinders, gaps 0.26-0.30 m
    geom = ObstacleMap.from_world(world.obstacles).geometry()
    route = Route(inflation_m=0.25)
    route.update(geom, world.start[:2], world.goal)
    clearance = min(ob.distance_m(x, y) for x, y in route.path for ob in world.obstacles)
    assert clearance > 0.25 - route.cell_m, clearance
    # the cost to go: the funnel's mouth (between the cylinders) costs more than going round
    funnel, round_ = np.array([[0.55, 0.0]]), np.array([[0.3, 0.7]])
    assert route.cost_to_go(funnel)[0] > route.cost_to_go(round_)[0]
    # no obstacles: the straight line, cost = distance
    route.update(None, (0.0, 0.0), (1.0, 0.0))
    assert route.cost_to_go(np.array([[0.0, 1.0]]))[0] == pytest.approx(math.sqrt(2.0))


def test_the_goal_bias_follows_the_cost_to_go_when_a_route_gives_one():
    sp = CFG.sampler
    sampler = TrajectorySampler(PerceptionCollisionChecker(K, T_GC, 0.5), sp, 0.25)
    ground = drawn_mask()
    goal = (1.0, 0.0)
    straight = sampler.select(ground, goal)
    assert straight.arc.curvature_per_m == 0.0
    # a route that says "the way to the goal is on the left" (everything right of y = 0.2 is dear)
    ctg = lambda xy: np.hypot(xy[:, 0] - goal[0], xy[:, 1] - goal[1]) + 10.0 * (xy[:, 1] < 0.2)
    left = sampler.select(ground, goal, cost_to_go=ctg)
    assert left.arc.curvature_per_m > 0


WORLD_11_S1_FREE = {-3.0: 0.06, -1.5: 0.10, 0.0: 0.16, 1.5: 0.20, 3.0: 0.20}


def arcs_near_the_goal(goal_disc_radius_m: float, free=WORLD_11_S1_FREE, goal=(0.29, -0.13),
                       cost_to_go=lambda xy: 1.0 - 2.0 * xy[:, 1]):
    """The sampler's own five arcs with the free lengths COBRA's mono run of world 11 seed 1 had at
    162 s, the goal 0.32 m ahead-right (0.12 m from its 0.2 m disc), and a route whose cost to go is
    lower to the left (it went round a phantom on the disc's edge). -> the chosen curvature."""
    s = TrajectorySampler(PerceptionCollisionChecker(K, T_GC, 0.09),
                          dataclasses.replace(CFG.sampler, goal_disc=True), None)
    s._head_arcs = lambda ground: [Arc(c, poses, sm, free_m=free[float(c)]) for c, poses, sm in s._arcs]
    sel = s.select(drawn_mask(), goal, cost_to_go=cost_to_go, goal_radius_m=goal_disc_radius_m)
    return sel.arc.curvature_per_m


def test_an_arc_entering_the_goal_disc_wins_over_the_route_round_a_phantom():
    assert arcs_near_the_goal(0.0) == pytest.approx(3.0)       # the goal's centre: the route, left, away
    assert arcs_near_the_goal(0.2) == pytest.approx(0.0)       # the straight arc is in the disc at 0.14 m


def test_free_to_the_disc_edge_is_not_long_enough():
    """Counting an arc free as far as the disc's edge as long enough was tried: depth world 0
    seed 0 then took a +1.5 /m arc with 0.58 m free (0.64 m needed) into a gap narrower than the
    body and stopped for good. Long enough stays: within goal_tie_m of the longest, or free as far
    as the goal's centre. Here the -1.5 /m arc, 0.65 m free, ends in the 0.3 m disc of a goal 0.9 m
    away (0.6 m to the disc's edge), the straight arc is free for 1.0 m and the tie is 0.3 m."""
    assert CFG.sampler.goal_tie_m == pytest.approx(0.3)
    free = {-3.0: 0.1, -1.5: 0.65, 0.0: 1.0, 1.5: 0.2, 3.0: 0.1}
    assert arcs_near_the_goal(0.3, free, (0.75, -0.5), None) == pytest.approx(0.0)
    free[-1.5] = 0.72                                          # within the tie: its prefix in the disc wins
    assert arcs_near_the_goal(0.3, free, (0.75, -0.5), None) == pytest.approx(-1.5)


def test_the_planner_passes_the_goal_radius_to_the_sampler(monkeypatch):
    """replan(goal_radius_m) reaches select (which honours it only with goal_disc)."""
    from snake_autonomy.planning.rectilinear import sampler as sampler_module
    seen, select = [], sampler_module.TrajectorySampler.select

    def spy(self, *args, **kwargs):
        seen.append(kwargs.get("goal_radius_m"))
        return select(self, *args, **kwargs)
    monkeypatch.setattr(sampler_module.TrajectorySampler, "select", spy)
    p = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(CFG.follower), COBRA)
    p.replan(0.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0), (0.35, -0.15), 0.2)
    p.replan(10.0, drawn_mask(), T_GC, (0.0, 0.0, 0.0), (0.35, -0.15))
    assert seen == [0.2, 0.0]


def test_among_arcs_entering_the_disc_the_one_passing_nearest_the_centre():
    """The 12-link robot's depth run of world 9 seed 5 at 102 s, the goal 0.48 m ahead-right
    (0.435, -0.207) in the ground frame. The -3 and -1.5 /m arcs both enter the 0.2 m disc; preferring
    the arc whose prefix ends in the disc took the -3 arc, the robot turned less tightly than that,
    missed the disc, and its tail touched a cylinder backing off. The arc passing nearest the
    centre (-1.5: 0.03 m, against 0.12 m) is taken, as without the disc."""
    free = {-3.0: 0.52, -1.5: 0.82, 0.0: 1.1, 1.5: 1.1, 3.0: 1.1}
    for radius in (0.0, 0.2):
        assert arcs_near_the_goal(radius, free, (0.435, -0.207), None) == pytest.approx(-1.5)
