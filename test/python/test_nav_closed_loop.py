"""Short closed-loop runs (runs/nav_batch.py NavRun: the planner, the C++ driver's gait and the
MuJoCo plant) on named random worlds and seeds, each replaying a failure the planner once had and
asserting the outcome that its fix gives: goals reached that were orbited, contacts avoided by the
finer classifier cells, the swing guard, the crawl room of a turn, the map's route and keeping the
turn's side. Each takes 10-40 s of wall time."""
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


def test_cobra_reaches_a_goal_it_used_to_orbit():
    """Random world 13 seed 0 (three cylinders across the line, the goal 0.4 m past the last).
    With the follower stopping at kappa 1 /m while the sampler planned arcs to 2 /m, COBRA ended
    `circling_goal` 0.14 m off the disc at 300 s; with the planned arcs ones the follower can drive it
    reached in 234 s, no contact (321 s once an obstacle in one earlier view wins), within COBRA's
    567 s limit. About 20-40 s wall."""
    m = _run(13, 0)
    assert m["goal_reached"] and m["collisions"] == 0 and m["outcome"] == "success"


def test_the_12_link_robot_reaches_a_goal_it_used_to_orbit():
    """Random world 9 seed 4: with kappa_max 2 the 12-link robot ended at the time limit 0.03 m
    off the disc; with kappa_max 3 all 100 runs of the 20 x 5 experiment reached. About 10-20 s wall."""
    m = _run(9, 4, robot="chang_rectilinear")
    assert m["goal_reached"] and m["collisions"] == 0 and m["outcome"] == "success"


def _truth_run(nav_config_over, stride_px):
    """COBRA in random world 0, seed 1, perception truth (the segmentation render through 40 px
    blocks judging cells of stride_px: the classifier's pipeline with a perfect classifier)."""
    cfg = nav_config_over(f"nav_{stride_px}.yaml", f"classifier: {{stride_px: {stride_px}}}\n"
                          "sampler: {blocked_wins: false, reshape_keeps_centroid: false, swing_guard_tail_m: 0.0}\n"
                          "map: {source: none, route: false}\n")   # without the later guards and map (reshaping
                                                                  # about the centroid, the tiles run reaches
                                                                  # without a contact too)
    m = NavRun(NavRunSpec(random_corridor(0), seed=1, perception="truth", time_limit_s=300.0,
                          nav_config=cfg, keep_frames=False)).run().metrics
    print({k: m[k] for k in ("goal_reached", "time_s", "collisions", "outcome", "stops_no_free_arc")})
    assert m["perception"] == "truth"
    return m


def test_with_tiles_cobra_touches_the_cylinder_at_the_image_edge_and_with_cells_it_does_not(nav_config_over):
    """40 px tiles: 16 contact episodes, time limit; 20 px cells: reached in 217 s, no contact, no
    stop. With the newest earlier view deciding (sampler.blocked_wins false; with blocked_wins the
    tiles run reached in 237 s without contact too). About 30 s wall for both."""
    assert _truth_run(nav_config_over, 40)["collisions"] > 0
    m = _truth_run(nav_config_over, 20)
    assert m["goal_reached"] and m["collisions"] == 0 and m["outcome"] == "success"


def test_cobra_passes_the_three_cylinders_of_world_6_without_its_front_links_touching(nav_config_over):
    """Random world 6 seed 4, depth. Without the swing guard the planner reached at 449 s with 21
    contact episodes (the head passed the right cylinder 0.18 m off, the left arc back to the goal
    swung link 1 into it). With the swing guard: reached without a contact (measured 470 s). ~30 s
    wall. Without the map and route (with them this run ends stopped in the funnel, no contact), with
    any obstacle in an earlier view winning and backing off unchecked (blocked_wins_depth_m .inf,
    back_off_check_m 0: with them it runs to the time limit, no contact), and reshaping about the
    middle (reshape_keeps_centroid on: reached with 6 contact episodes; without the map the tail guard
    does nothing)."""
    world = random_corridor(6)
    cfg = nav_config_over("no_map.yaml", "map: {source: none, route: false}\n"
                          "sampler: {blocked_wins_depth_m: .inf, back_off_check_m: 0.0, reshape_keeps_centroid: false,"
                          " swing_guard_tail_m: 0.0}\n")
    m = NavRun(NavRunSpec(world, seed=4, time_limit_s=567.0, keep_frames=False, nav_config=cfg)).run().metrics
    print({k: m[k] for k in ("goal_reached", "time_s", "collisions", "min_clearance_m", "outcome")})
    assert m["goal_reached"] and m["collisions"] == 0, m["outcome"]


def test_cobra_backs_off_instead_of_turning_its_head_into_the_cylinder_of_world_6_seed_2(nav_config_over):
    """Random world 6 seed 2, depth. Without turn_free_m (a turn needs no room to crawl) it stopped 0.41 m short of a
    cylinder, turned in place left, and at the next replan (every arc 0.00 m free, the cylinder
    right ahead) kept turning: base_link touched it at 103 s (6 episodes by 123 s). With
    turn_free_m it backs off there instead; no contact (measured: none in the whole 567 s run).
    Both runs to 160 s, ~15 s wall."""
    # both without the map
    off = nav_config_over("off.yaml", "sampler: {turn_free_m: 0.0}\nmap: {source: none, route: false}\n")
    on = nav_config_over("on.yaml", "map: {source: none, route: false}\n")
    runs = {}
    for name, cfg in (("on", on), ("off", off)):
        runs[name] = NavRun(NavRunSpec(random_corridor(6), seed=2, time_limit_s=160.0, nav_config=cfg,
                                       keep_frames=False)).run()
    on, off_run = runs["on"], runs["off"]
    assert off_run.metrics["collisions"] > 0 and off_run.metrics["contacts_turn_in_place"] > 0
    assert on.metrics["collisions"] == 0, on.metrics
    assert any("no turn the body can sweep: back off" in r.reason and
               max(a.free_m for a in r.selection.arcs) < 0.05 for r in on.replans)


def test_cobra_goes_round_world_6_instead_of_into_its_funnel(nav_config_over):
    """Random world 6 (three cylinders, gaps 0.26-0.30 m: narrower than COBRA's 0.5 m checked
    footprint), seed 7, depth. Without the map COBRA drove into the funnel, stopped, and touched at
    103 s (75 episodes over seeds 7-9). With config/nav.yaml's map and route it went round the
    cluster: the goal at 286 s, no contact (~25 s wall). The map's priors laid on their own view's
    floor too (with map.priors_off_own_floor, as nav.yaml has it, the gaps look wider in the map and
    this run stops in the funnel: 31 stops to 400 s, no contact). Both runs reshape about the middle
    without the body and crawl guards (with them this run reaches the time limit, no contact)."""
    committed = NavConfig.from_yaml().map
    assert (committed.source, committed.route) == ("faces", True)
    no_body_guards = ("sampler: {reshape_keeps_centroid: false, swing_guard_body: false, crawl_guard_m: 0.0, "
                      "crawl_blocked_backs_off: false}\n")
    off = nav_config_over("off.yaml", f"map: {{source: none, route: false}}\n{no_body_guards}")
    before = NavRun(NavRunSpec(random_corridor(6), seed=7, time_limit_s=120.0, nav_config=off,
                               keep_frames=False)).run()
    assert before.metrics["collisions"] > 0, before.metrics
    own = nav_config_over("priors_on_own_floor.yaml", f"map: {{priors_off_own_floor: false}}\n{no_body_guards}")
    run = NavRun(NavRunSpec(random_corridor(6), seed=7, time_limit_s=400.0, keep_frames=False, nav_config=own))
    result = run.run()
    assert result.metrics["outcome"] == "success", result.metrics
    # it went round (south of the cluster's lowest cylinder or north of its highest), not between
    ys = result.trajectory[:, 2]
    lows = [ob.y_m - ob.radius_m for ob in random_corridor(6).obstacles]
    highs = [ob.y_m + ob.radius_m for ob in random_corridor(6).obstacles]
    assert ys.min() < min(lows) or ys.max() > max(highs), (ys.min(), ys.max())
    assert all(r.route_world is not None for r in result.replans)


def test_cobra_world_4_seed_3_backs_off_instead_of_swinging_its_head_back(nav_config_over):
    """Random world 4 seed 3, depth. Turning to either side, at 112 s it turned in place
    right (kappa -1.5), at 122 s left (+1.5), swinging the head ~0.2 m each way beside a cylinder;
    backing off at 132 s base_link touched obstacle_1. Keeping the side, no contact to 150 s (the
    whole run: goal reached, measured in the 20x5 experiment). Both runs to 150 s: turn_keeps_side
    off (with blocked_wins_depth_m .inf, back_off_check_m 0 and map.priors_off_own_floor false: with
    nav.yaml's values this run has no contact to 150 s either way) and nav.yaml's."""
    runs = {}
    for on in (False, True):
        cfg = nav_config_over(f"keep_{on}.yaml",
                              "" if on else "sampler: {turn_keeps_side: false, blocked_wins_depth_m: .inf, "
                                            "back_off_check_m: 0.0}\nmap: {priors_off_own_floor: false}\n")
        runs[on] = NavRun(NavRunSpec(random_corridor(4), seed=3, time_limit_s=150.0, nav_config=cfg,
                                     keep_frames=False)).run()
    turns = lambda run: [r.reason for r in run.replans if "turn in place (kappa" in r.reason]
    off, on = runs[False], runs[True]
    assert off.metrics["collisions"] > 0, off.metrics
    assert any("+1.50" in t for t in turns(off)) and any("-1.50" in t for t in turns(off)), turns(off)
    assert on.metrics["collisions"] == 0, on.metrics
