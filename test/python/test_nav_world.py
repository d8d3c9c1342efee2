"""World files (sim/world.py) and their MuJoCo scene (sim/scene.py, sim/collisions.py)."""
import math

import pytest

from snake_autonomy.sim.world_file import World, WorldError, load_world

GOOD = {"start": [0.0, 0.0, 90.0], "goal": [3.0, 0.5], "goal_radius_m": 0.3,
        "obstacles": [{"type": "cylinder", "x": 1.0, "y": 0.2, "radius_m": 0.1, "height_m": 0.3},
                      {"type": "box", "x": 2.0, "y": -0.3, "size_m": [0.2, 0.4, 0.3], "yaw_deg": 30}],
        "floor_texture": "checker"}


def test_good_world_loads_with_the_contract_fields(root):
    w = World.from_dict(GOOD)
    assert w.start_rad == pytest.approx((0.0, 0.0, math.pi / 2))
    assert w.goal == (3.0, 0.5) and w.goal_radius_m == 0.3
    assert [o.kind for o in w.obstacles] == ["cylinder", "box"]
    assert w.obstacles[1].size_m == (0.2, 0.4, 0.3) and w.obstacles[1].yaw_deg == 30
    assert w.goal_reached(3.1, 0.6) and not w.goal_reached(2.5, 0.5)
    assert World.from_dict(w.to_dict()).to_dict() == w.to_dict()
    shipped = load_world(root / "config" / "worlds" / "corridor.yaml")
    assert len(shipped.obstacles) == 5


def test_bad_world_lists_every_problem():
    bad = {"start": [0, 0], "goal": [1, "x"], "goal_radius_m": -1, "colour": "red",
           "floor_texture": "lava",
           "obstacles": [{"type": "cone", "x": 1, "y": 1},
                         {"type": "cylinder", "x": 1, "radius_m": 0, "height_m": 0.3, "yaw_deg": 3},
                         {"type": "box", "x": 1, "y": 2, "size_m": [1, 2]}]}
    with pytest.raises(WorldError) as e:
        World.from_dict(bad, "bad.yaml")
    text = "\n".join(e.value.problems)
    for needle in ("start:", "goal[1]: must be a finite number (m), got 'x'",
                   "goal_radius_m: must be a number in (0, 10] m, got -1", "colour: unknown key",
                   "floor_texture: unknown texture 'lava'", "obstacles[0].type: must be cylinder or box, got 'cone'",
                   "obstacles[1].y:", "obstacles[1].radius_m: must be a number in (0, 10] m, got 0",
                   "obstacles[1].yaw_deg: unknown key", "obstacles[2].size_m:"):
        assert needle in text, (needle, text)
    assert len(e.value.problems) == 10


def test_obstacle_on_start_or_goal_is_refused():
    d = dict(GOOD, obstacles=[{"type": "cylinder", "x": 0.0, "y": 0.0, "radius_m": 0.2, "height_m": 0.3},
                              {"type": "box", "x": 3.0, "y": 0.5, "size_m": [0.2, 0.2, 0.2]}])
    with pytest.raises(WorldError) as e:
        World.from_dict(d)
    assert any("covers the start" in p for p in e.value.problems)
    assert any("covers the goal" in p for p in e.value.problems)


def test_scene_obstacles_are_named_and_collisions_counted_per_episode(cobra_yaml):
    from snake_autonomy import _core
    from snake_autonomy.sim.collisions import CollisionMonitor
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.sim.plant import Plant
    from snake_autonomy.sim.scene import build_scene
    robot = _core.RobotModel.from_yaml(cobra_yaml)
    params = SimConfig.from_yaml(str(_config("sim.yaml"))).draw(seed=0)
    # an obstacle resting across link 4 (x about -0.5 m): in contact from the first step
    w = World.from_dict({"start": [0, 0, 0], "goal": [3, 0], "goal_radius_m": 0.3,
                         "obstacles": [{"type": "box", "x": -0.5, "y": 0.0, "size_m": [0.1, 0.4, 0.2]},
                                       {"type": "cylinder", "x": 1.0, "y": 1.0, "radius_m": 0.1,
                                        "height_m": 0.2}]})
    scene = build_scene(w)
    plant = Plant(robot, params, w.start_rad, scene_xml=scene.scene_xml, assets_xml=scene.assets_xml)
    names = [plant.model.geom(g).name for g in range(plant.model.ngeom)]
    assert "obstacle_0" in names and "obstacle_1" in names
    mon = CollisionMonitor(plant.model)
    plant.step(0.01)
    assert mon.update(plant.data) >= 1
    first = mon.collisions
    # each episode says which obstacle and which link, and where: the box across links 3-5
    assert len(mon.episodes) == first
    e = mon.episodes[0]
    assert e.obstacle == "obstacle_0" and e.link.startswith("link_") and e.t_s == plant.data.time
    assert -0.75 < e.x_m < -0.25 and abs(e.y_m) < 0.05
    plant.step(0.01)
    assert mon.update(plant.data) == 0            # same episode: not counted again
    assert mon.collisions == first
    assert mon.min_clearance_m == 0.0
    # a flicker (apart for less than gap_s) is the same episode; apart for longer, a new one
    pairs = set(mon._touching)
    mon._touching = set()
    mon._last_seen = {p: plant.data.time - 0.1 for p in pairs}
    assert mon.update(plant.data) == 0
    mon._touching = set()
    mon._last_seen = {p: plant.data.time - 0.5 for p in pairs}
    assert mon.update(plant.data) == len(pairs)
    assert len(mon.episodes) == mon.collisions


def _config(name):
    from pathlib import Path
    return Path(__file__).resolve().parents[2] / "config" / name


def test_world_coordinates_and_sizes_are_bounded_naming_key_and_value():
    bad = dict(GOOD, start=[0.0, -500.0, 1e9], goal=[1e15, 0.5], goal_radius_m=1e300,
               obstacles=[{"type": "cylinder", "x": 1e300, "y": 0.2, "radius_m": 0.1, "height_m": 0.3},
                          {"type": "cylinder", "x": 1.0, "y": 0.2, "radius_m": 50.0, "height_m": 1e6},
                          {"type": "box", "x": 2.0, "y": -300.0, "size_m": [0.2, 1e3, 0.3], "yaw_deg": 1e20}])
    with pytest.raises(WorldError) as e:
        World.from_dict(bad, "big.yaml")
    text = "\n".join(e.value.problems)
    for needle in ("start[1]: must be within +-100 m, got -500", "start[2]: must be within +-360 deg, got 1e+09",
                   "goal[0]: must be within +-100 m, got 1e+15",
                   "goal_radius_m: must be a number in (0, 10] m, got 1e+300",
                   "obstacles[0].x: must be within +-100 m, got 1e+300",
                   "obstacles[1].radius_m: must be a number in (0, 10] m, got 50",
                   "obstacles[1].height_m: must be a number in (0, 10] m, got 1e+06",
                   "obstacles[2].y: must be within +-100 m, got -300",
                   "obstacles[2].size_m[1]: must be a number in (0, 10] m, got 1000",
                   "obstacles[2].yaw_deg: must be within +-360 deg, got 1e+20"):
        assert needle in text, (needle, text)


def test_world_problems_quote_a_short_piece_of_a_value():
    with pytest.raises(WorldError) as e:
        World.from_dict(dict(GOOD, colour="x" * 500, floor_texture="\x1b[2J" + "y" * 500), "long.yaml")
    text = str(e.value)
    assert "colour: unknown key" in text and "floor_texture: unknown texture" in text
    assert "x" * 61 not in text and "y" * 61 not in text and "\x1b" not in text


def test_check_world_refuses_a_far_goal_naming_it(tmp_path, capsys):
    import yaml
    from snake_autonomy.cli import main as cli_main
    far = tmp_path / "far.yaml"
    far.write_text(yaml.safe_dump(dict(GOOD, goal=[1e15, 0.5], goal_radius_m=1e300)))
    assert cli_main(["nav", "check-world", str(far)]) == 1
    err = capsys.readouterr().err
    assert str(far) in err and "goal[0]: must be within +-100 m, got 1e+15" in err


def test_the_route_grid_is_bounded_and_refused_before_allocating():
    """A goal 150 m away took 3.85 GB in the route's grid; now refused naming the extent. Run in a
    process capped at 1 GB of address space, so that an unbounded grid fails there."""
    import subprocess
    import sys
    import textwrap
    script = textwrap.dedent("""
        import resource, time
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
        import shapely
        from snake_autonomy.planning.rectilinear.route import Route
        route = Route(cell_m=0.04, max_cells=1_000_000)
        wall = shapely.box(5.0, -1.0, 5.2, 1.0)
        route.update(wall, (0.0, 0.0), (3.0, 0.5))          # a few metres: fine
        assert route.path is not None
        t0 = time.perf_counter()
        try:
            route.update(wall, (0.0, 0.0), (150.0, 150.0))
        except ValueError as exc:
            print(f"{time.perf_counter() - t0:.3f}")
            print(exc)
    """)
    try:
        proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        pytest.fail("the 150 m route grid was not refused within 120 s")
    assert proc.returncode == 0 and proc.stdout, proc.stderr[-1500:]
    seconds, message = proc.stdout.split("\n", 1)
    assert float(seconds) < 0.5
    assert "route grid" in message and "152.0 m x 152.0 m" in message and "map.route_max_cells" in message
