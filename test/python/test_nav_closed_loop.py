"""Whole runs of the robot's navigation loop (runs/nav_batch.py NavRun: NavLoop fed as planner_node is,
the C++ driver's gait, the MuJoCo plant) on named random corridors: the goal reached, at rest inside
its disc, without a contact. Each mechanism on its own: test_nav_swing_guard, test_nav_crawl_guard,
test_nav_turn_in_place, test_nav_back_off, test_nav_obstacle_map, test_nav_route_and_goal. Each run
takes 10-40 s of wall time."""
from snake_autonomy.planning.rectilinear.config import NavConfig, nav_config_path
from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
from snake_autonomy.runs.nav_experiment import random_corridor, time_limit_s


def _run(world_index, seed, robot="cobra"):
    """One run at the experiment's time limit for the robot (3 x its straight-line time)."""
    world = random_corridor(world_index)
    limit = time_limit_s(world, NavConfig.from_yaml(nav_config_path(robot)).follower.speed_m_s)
    result = NavRun(NavRunSpec(world, robot=robot, seed=seed, time_limit_s=limit, keep_frames=False)).run()
    m = result.metrics
    print({k: m[k] for k in ("goal_reached", "time_s", "collisions", "outcome", "closest_to_goal_m")})
    return m


def test_cobra_reaches_a_goal_just_past_three_cylinders():
    """Random world 13 seed 0 (three cylinders across the line, the goal 0.4 m past the last): the
    goal needs the turn to start among the cylinders (planned arcs the follower can drive). Measured
    with the one loop: reached at 253 s, no contact, within COBRA's 567 s limit. About 20-40 s wall."""
    m = _run(13, 0)
    assert m["goal_reached"] and m["collisions"] == 0 and m["outcome"] == "success"


def test_the_12_link_robot_reaches_a_goal_it_must_turn_tightly_for():
    """Random world 9 seed 4: with kappa_max 2 /m the 12-link robot ended at the time limit 0.03 m
    off the disc; its nav config's kappa_max 3 /m reaches it. About 10-20 s wall."""
    m = _run(9, 4, robot="chang_rectilinear")
    assert m["goal_reached"] and m["collisions"] == 0 and m["outcome"] == "success"
