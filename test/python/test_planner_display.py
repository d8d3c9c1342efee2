"""planner_display: the obstacle map rasterised into nav/map's OccupancyGrid (the cells a known
polygon covers, the grid's bound), the traversability mask, a world's ground-truth markers, the
simulated robot's contacts as markers; rviz/nav.rviz displays every one of these topics."""
import math

import numpy as np
import pytest
from shapely.geometry import Point, box

pytest.importorskip("nav_msgs.msg")
pytest.importorskip("visualization_msgs.msg")

from snake_autonomy.nodes.planner_display import (FREE, OCCUPIED, contact_markers, grid_window,  # noqa: E402
                                                  local_grid, occupancy, rasterise, traversability_mask,
                                                  world_markers)
from snake_autonomy.runs.recorded_topics import CONTACT_TEXT  # noqa: E402
from snake_autonomy.sim.collisions import ContactEpisode  # noqa: E402
from snake_autonomy.planning.rectilinear.local_map import LocalMap, LocalMapParams  # noqa: E402
from snake_autonomy.sim.world_file import World  # noqa: E402
from visualization_msgs.msg import Marker  # noqa: E402

CELL = 0.04


def test_a_square_occupies_exactly_the_cells_whose_centres_it_covers():
    square = box(0.2, 0.4, 0.36, 0.52)           # 4 x 3 cells of 4 cm, on cell edges
    grid = rasterise(square, (0.0, 0.0), (20, 20), CELL)
    rows, cols = np.nonzero(grid == OCCUPIED)
    assert sorted(set(cols)) == [5, 6, 7, 8]      # x 0.2..0.36: columns 5..8
    assert sorted(set(rows)) == [10, 11, 12]      # y 0.4..0.52: rows 10..12 (row-major, y up)
    assert len(rows) == 12
    assert np.all((grid == OCCUPIED) | (grid == FREE))


def test_a_disc_is_occupied_at_its_centre_and_free_beyond_its_radius():
    disc = Point(1.0, -0.5).buffer(0.2, 32)
    origin, (nx, ny) = grid_window(disc, (0.0, 0.0), (2.0, 0.0), CELL, 1.0)
    grid = rasterise(disc, origin, (nx, ny), CELL)
    xs = origin[0] + (np.arange(nx) + 0.5) * CELL
    ys = origin[1] + (np.arange(ny) + 0.5) * CELL
    X, Y = np.meshgrid(xs, ys)
    r = np.hypot(X - 1.0, Y + 0.5)
    assert np.all(grid[r < 0.19] == OCCUPIED)
    assert np.all(grid[r > 0.21] == FREE)


def test_the_window_covers_map_robot_and_goal_padded_on_cell_multiples():
    origin, (nx, ny) = grid_window(box(1.0, 1.0, 1.5, 1.2), (0.0, 0.0), (-2.0, 0.5), CELL, 1.0)
    assert origin[0] == pytest.approx(-3.0) and origin[1] == pytest.approx(-1.0)
    top = np.array(origin) + CELL * np.array([nx, ny])       # (2.5, 2.2) up to the next cell edge
    assert top[0] == pytest.approx(2.52) and top[1] == pytest.approx(2.2)
    for v in origin:
        assert abs(v / CELL - round(v / CELL)) < 1e-9


def test_the_grid_is_capped_around_the_robot():
    far = box(100.0, 0.0, 100.2, 0.2)             # 100 m away: 2550 cells at 4 cm, capped at 50
    origin, (nx, ny) = grid_window(far, (3.0, 0.0), None, CELL, 1.0, max_cells_per_side=50)
    assert nx == 50 and ny <= 50
    assert origin[0] <= 3.0 <= origin[0] + nx * CELL      # the robot inside the capped window
    grid = rasterise(far, origin, (nx, ny), CELL)
    assert not np.any(grid == OCCUPIED)                   # the far obstacle lies beyond the cap
    msg = occupancy(far, (3.0, 0.0), None, CELL, 1.0, 0, "map", max_cells_per_side=50)
    assert (msg.info.width, msg.info.height) == (nx, ny) and len(msg.data) == nx * ny


def test_the_occupancy_grid_message_places_the_obstacle_in_the_world_frame():
    square = box(0.52, 0.12, 0.68, 0.28)
    msg = occupancy(square, (0.0, 0.0), (1.0, 0.0), CELL, 0.5, 0, "map")
    assert msg.header.frame_id == "map" and msg.info.resolution == pytest.approx(CELL)
    grid = np.array(msg.data, np.int8).reshape(msg.info.height, msg.info.width)
    j, i = np.nonzero(grid == OCCUPIED)
    x = msg.info.origin.position.x + (i + 0.5) * CELL
    y = msg.info.origin.position.y + (j + 0.5) * CELL
    assert len(x) == 16
    assert np.all((x > 0.52) & (x < 0.68) & (y > 0.12) & (y < 0.28))
    empty = occupancy(None, (0.0, 0.0), None, CELL, 0.5, 0, "map")
    assert set(empty.data) == {FREE} and empty.info.width == 26


def test_the_local_map_message_places_its_cells_in_the_world_frame_with_unknown_ones():
    m = LocalMap(LocalMapParams(size_m=2.0))
    m._place((1.0, 0.5))
    i, j, _ = m.cells(np.array([[1.3, 0.7]]))
    m.log_odds[i, j] = 3.0                                         # occupied
    m.log_odds[i - 5, j] = -1.0                                    # seen as floor 0.2 m nearer in x
    msg = local_grid(m, 0, "map")
    grid = np.array(msg.data, np.int8).reshape(msg.info.height, msg.info.width)
    jj, ii = np.nonzero(grid == OCCUPIED)
    x = msg.info.origin.position.x + (ii + 0.5) * msg.info.resolution
    y = msg.info.origin.position.y + (jj + 0.5) * msg.info.resolution
    assert len(x) == 1 and abs(x[0] - 1.3) <= 0.021 and abs(y[0] - 0.7) <= 0.021   # within half a cell
    assert (grid == FREE).sum() == 1 and (grid == -1).sum() == grid.size - 2
    assert local_grid(LocalMap(), 0, "map").info.width == 0           # no view yet: an empty grid


def test_the_mask_is_mono8_255_on_ground():
    ground = np.zeros((4, 6), bool)
    ground[2:, :] = True
    msg = traversability_mask(ground, 0, "camera_color_optical_frame")
    assert (msg.encoding, msg.width, msg.height) == ("mono8", 6, 4)
    img = np.frombuffer(msg.data, np.uint8).reshape(4, 6)
    assert np.all(img[2:] == 255) and np.all(img[:2] == 0)


def test_world_markers_show_every_obstacle_and_the_goal_disc():
    world = World.from_dict({
        "start": [0, 0, 0], "goal": [2.0, 0.5], "goal_radius_m": 0.3,
        "obstacles": [{"type": "cylinder", "x": 1.0, "y": 0.2, "radius_m": 0.1, "height_m": 0.3},
                      {"type": "box", "x": 1.5, "y": -0.3, "size_m": [0.2, 0.4, 0.25], "yaw_deg": 90}]})
    markers = world_markers(world, 0, "map").markers
    assert markers[0].action == Marker.DELETEALL
    cyl, cube, goal = markers[1:]
    assert all(m.header.frame_id == "map" and m.action == Marker.ADD for m in markers[1:])
    assert (cyl.type, cyl.pose.position.x, cyl.scale.x, cyl.scale.z) == (Marker.CYLINDER, 1.0, 0.2, 0.3)
    assert cyl.pose.position.z == pytest.approx(0.15)                     # standing on the floor
    assert (cube.type, cube.scale.x, cube.scale.y, cube.scale.z) == (Marker.CUBE, 0.2, 0.4, 0.25)
    assert 2 * math.atan2(cube.pose.orientation.z, cube.pose.orientation.w) == pytest.approx(math.pi / 2)
    assert (goal.type, goal.pose.position.x, goal.pose.position.y) == (Marker.CYLINDER, 2.0, 0.5)
    assert goal.scale.x == pytest.approx(0.6)
    assert len({(m.ns, m.id) for m in markers[1:]}) == 3


def test_contact_markers_hold_every_episode_where_its_link_touched():
    episodes = [ContactEpisode(1.0, "obstacle_0", "link_3", 0.4, -0.1),
                ContactEpisode(2.5, "obstacle_2", "base_link", 1.2, 0.3)]
    markers = contact_markers(episodes, 0, "map").markers
    assert [(m.id, m.type, m.header.frame_id) for m in markers] == [(0, Marker.SPHERE, "map"),
                                                                    (1, Marker.SPHERE, "map")]
    assert [(m.pose.position.x, m.pose.position.y) for m in markers] == [(0.4, -0.1), (1.2, 0.3)]
    assert [m.text.split(CONTACT_TEXT) for m in markers] == [["link_3", "obstacle_0"], ["base_link", "obstacle_2"]]
    assert all(m.pose.position.z > 0 and m.scale.x > 0 and m.color.a > 0 for m in markers)
    assert contact_markers([], 0, "map").markers == []


def test_the_navigation_rviz_config_displays_every_topic_of_the_planner_and_the_simulated_world(root):
    import yaml
    cfg = yaml.safe_load((root / "rviz" / "nav.rviz").read_text())
    displays = cfg["Visualization Manager"]["Displays"]
    enabled = {d.get("Topic") or d.get("Marker Topic") or d.get("Image Topic"): d.get("Enabled") for d in displays}
    shown = {"nav/map", "nav/path", "nav/route", "nav/arcs", "nav/goal", "nav/traversability", "viz/path",
             "sim/world_markers", "sim/contact_markers"}
    assert {topic: enabled.get(topic) for topic in shown} == dict.fromkeys(shown, True)
    assert "nav/traversability_mask" in enabled          # configured, off at start (the overlay shows the same)
    tools = cfg["Visualization Manager"]["Tools"]
    assert {"Class": "rviz/SetGoal", "Topic": "move_base_simple/goal"}.items() <= next(
        t for t in tools if t["Class"] == "rviz/SetGoal").items()
