"""The generated BARN-like world family (sim/nav_worlds.py) and the CLI around the world families
(nav experiment --world-files, nav worlds). No simulation: every check is on the world's geometry,
the footprint path re-checked with shapely, independently of the generator's grid."""
import math
import os
import subprocess
import sys

import pytest
import yaml
from shapely.geometry import LineString, Point, Polygon, box
from shapely.ops import unary_union

from snake_autonomy._core import RobotModel
from snake_autonomy.paths import robot_yaml
from snake_autonomy.sim.nav_worlds import barn_layout, barn_world
from snake_autonomy.sim.world_file import World, load_world

# (footprint half-width = the nav config's sampler.body_clearance_m, body length behind base_link)
ROBOTS = {"cobra": (0.25, 1.55), "chang_rectilinear": (0.15, 0.87)}
INDICES = (0, 1, 2, 3, 4, 100, 101, 102)
CASES = [(robot, k) for robot in ROBOTS for k in INDICES]


def layout(robot, k):
    hw, length = ROBOTS[robot]
    return barn_layout(k, hw, body_length_m=length)


def footprints(world):
    return [Polygon(ob.corners()) for ob in world.obstacles]


def test_the_same_index_gives_the_same_world_and_indices_differ():
    for hw, length in ROBOTS.values():
        a = barn_world(3, hw, body_length_m=length).to_dict()
        assert a == barn_world(3, hw, body_length_m=length).to_dict()
        assert a != barn_world(4, hw, body_length_m=length).to_dict()
        assert a["name"] == "barn_003"
    assert barn_world(0).floor_texture != barn_world(1).floor_texture


@pytest.mark.parametrize("robot,k", CASES)
def test_a_field_is_15_to_30_percent_boxes_inside_the_field(robot, k):
    b = layout(robot, k)
    (x0, y0), (sx, sy) = b.origin_m, b.size_m
    field = box(x0, y0, x0 + sx, y0 + sy)
    obstacles = unary_union(footprints(b.world))
    assert all(ob.kind == "box" for ob in b.world.obstacles)
    assert field.buffer(1e-6).contains(obstacles)
    assert 0.15 <= obstacles.area / field.area <= 0.30
    assert math.isclose(obstacles.area / field.area, b.fill, abs_tol=1e-6)
    assert sx * sy >= 0.9 * 5.0 * 4.0


@pytest.mark.parametrize("robot,k", CASES)
def test_goal_far_start_body_free_and_a_footprint_wide_path(robot, k):
    hw, length = ROBOTS[robot]
    b = layout(robot, k)
    w = b.world
    (sx, sy, heading), (gx, gy) = w.start_rad, w.goal
    assert math.hypot(gx - sx, gy - sy) >= 3.0
    # the start heads at the goal within +-30 deg
    off = math.atan2(gy - sy, gx - sx) - heading
    assert abs(math.atan2(math.sin(off), math.cos(off))) <= math.radians(30.0) + 1e-3
    obstacles = unary_union(footprints(w))
    # the body lying straight behind base_link, footprint-wide, touches nothing
    body = LineString([(sx, sy), (sx - length * math.cos(heading), sy - length * math.sin(heading))])
    assert obstacles.distance(body) >= hw
    assert obstacles.distance(Point(gx, gy)) >= hw
    # the free space of a disc of radius hw within the field: start and goal in one component of it
    (x0, y0), (fx, fy) = b.origin_m, b.size_m
    free = box(x0, y0, x0 + fx, y0 + fy).difference(obstacles.buffer(hw))
    parts = list(getattr(free, "geoms", [free]))
    start_part = [p for p in parts if p.intersects(Point(sx, sy))]
    assert len(start_part) == 1 and start_part[0].intersects(Point(gx, gy))
    assert b.passage_m >= 2 * hw


def test_the_smaller_robot_gets_denser_fields():
    counts = {robot: sum(len(layout(robot, k).world.obstacles) for k in INDICES) for robot in ROBOTS}
    assert counts["chang_rectilinear"] > counts["cobra"]
    assert max(len(layout(robot, k).world.obstacles) for robot, k in CASES) <= 200


def test_world_round_trips_through_its_dict_and_a_yaml_file(tmp_path):
    w = barn_world(7)
    again = World.from_dict(w.to_dict(), "again")
    assert again.to_dict() == w.to_dict()
    path = tmp_path / "barn_007.yaml"
    path.write_text(yaml.safe_dump(w.to_dict(), sort_keys=False))
    assert load_world(path).to_dict() == w.to_dict()


def test_no_field_with_a_path_is_a_clear_error():
    with pytest.raises(ValueError, match=r"barn_world\(0\): no field with a path .* 2 tries"):
        barn_layout(0, robot_clearance_m=0.7, cell_m=0.25, field_m=(6.0, 6.0), fill_range=(0.28, 0.3), max_tries=2)


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "snake_autonomy.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=120, env={**os.environ, "MPLBACKEND": "Agg"})


def test_world_files_matching_nothing_exit_2_naming_the_glob(tmp_path):
    pattern = str(tmp_path / "none" / "*.yaml")
    proc = run_cli("nav", "experiment", "--world-files", pattern, "--out", tmp_path / "out")
    assert proc.returncode == 2, proc.stderr
    assert pattern in proc.stderr and "Traceback" not in proc.stderr
    (tmp_path / "bad.yaml").write_text("start: [0, 0]\n")
    proc = run_cli("nav", "experiment", "--world-files", tmp_path / "b*.yaml", "--out", tmp_path / "out")
    assert proc.returncode == 2 and str(tmp_path / "bad.yaml") in proc.stderr


def test_nav_worlds_writes_loadable_world_files_and_top_views(tmp_path):
    proc = run_cli("nav", "worlds", "--family", "barn", "--first-world", "100", "--worlds", "2",
                   "--robot", "chang_rectilinear", "--out", tmp_path)
    assert proc.returncode == 0, proc.stderr
    files = sorted(tmp_path.glob("*.yaml"))
    assert [f.name for f in files] == ["barn_100.yaml", "barn_101.yaml"]
    assert sorted(f.name for f in tmp_path.glob("*.png")) == ["barn_100.png", "barn_101.png"]
    # the files are the family's worlds for the 12-link robot (its nav config's footprint, its length)
    m = RobotModel.from_yaml(str(robot_yaml("chang_rectilinear")))
    length = m.head_length_m + m.num_joints * m.link_length_m + m.link_radius_m
    assert load_world(files[0]).to_dict() == barn_world(100, 0.15, body_length_m=length).to_dict()
