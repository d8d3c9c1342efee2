"""What the navigation knows, and the simulated world it moves in, as rviz messages. Pure message
builders: no node, no master (planner_node and sim_node publish them).

- occupancy(): the planner's obstacle map (planning/rectilinear/obstacle_map.py ObstacleMap.geometry())
  rasterised on a grid of map.cell_m cells -> nav_msgs/OccupancyGrid (nav/map).
- local_grid(): the layered planner's local map (planning/rectilinear/local_map.py LocalMap: occupied,
  free as the views showed it, unknown) -> nav_msgs/OccupancyGrid (nav/map).
- traversability_mask(): a replan's traversability image -> sensor_msgs/Image mono8
  (nav/traversability_mask: 255 ground, 0 not).
- world_markers(): a world file's obstacles and goal disc (sim/world_file.py World) ->
  visualization_msgs/MarkerArray (sim/world_markers: the simulation's ground truth, not what the
  planner knows).
- contact_marker(): one contact episode of the simulated robot (sim/contacts);
  contact_markers(): every episode so far (sim/contact_markers, latched, shown in rviz/nav.rviz).
"""
import math
from typing import Optional, Tuple

import numpy as np
import shapely
from geometry_msgs.msg import Quaternion
from nav_msgs.msg import OccupancyGrid
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from snake_autonomy.nodes.image_msgs import to_image
from snake_autonomy.nodes.viz_markers import _marker
from snake_autonomy.runs.recorded_topics import CONTACT_TEXT

OCCUPIED, FREE = 100, 0
MAX_CELLS_PER_SIDE = 1000      # nav/map: at most 1000 x 1000 cells (40 m x 40 m at 4 cm; 1 MB a message)
OBSTACLE_COLOUR = ColorRGBA(0.55, 0.35, 0.2, 0.8)
GOAL_COLOUR = ColorRGBA(0.1, 0.8, 0.3, 0.4)     # the world's goal disc (planner_goals' nav/goal is blue)
GOAL_HEIGHT_M = 0.005


def grid_window(geometry, robot_xy, goal_xy: Optional[Tuple[float, float]], cell_m: float, pad_m: float,
                max_cells_per_side: int = MAX_CELLS_PER_SIDE):
    """(origin (x, y) of the grid's corner, (nx, ny) cells): the box around the map's geometry (if not
    empty), the robot and the goal (if any), grown by pad_m, its corner on a multiple of cell_m (the
    grid does not shift between replans). A side longer than max_cells_per_side cells is cut to that
    many, centred on the robot (clipped to the box): the map near the robot is what is shown."""
    pts = [np.asarray(robot_xy, float)[:2]]
    if goal_xy is not None:
        pts.append(np.asarray(goal_xy, float)[:2])
    if geometry is not None and not geometry.is_empty:
        x0, y0, x1, y1 = geometry.bounds
        pts += [np.array([x0, y0]), np.array([x1, y1])]
    pts = np.array(pts)
    lo = np.floor((pts.min(axis=0) - pad_m) / cell_m + 1e-9)   # 1e-9: a bound on a cell's edge stays there
    hi = np.ceil((pts.max(axis=0) + pad_m) / cell_m - 1e-9)
    n = (hi - lo).astype(np.int64)
    robot = np.floor(np.asarray(robot_xy, float)[:2] / cell_m)
    for k in range(2):
        if n[k] > max_cells_per_side:
            start = np.clip(robot[k] - max_cells_per_side // 2, lo[k], hi[k] - max_cells_per_side)
            lo[k], n[k] = start, max_cells_per_side
    return lo * cell_m, (int(n[0]), int(n[1]))


def rasterise(geometry, origin_xy, shape, cell_m: float) -> np.ndarray:
    """(ny, nx) int8, row-major as OccupancyGrid's data (row j: y = origin y + (j + 0.5) cell_m):
    OCCUPIED where geometry covers the cell's centre (shapely.contains_xy), FREE elsewhere. Only the
    cells under the geometry's bounding box are tested."""
    nx, ny = shape
    grid = np.full((ny, nx), FREE, np.int8)
    if geometry is None or geometry.is_empty:
        return grid
    ox, oy = origin_xy
    x0, y0, x1, y1 = geometry.bounds
    i0, i1 = max(0, int(math.floor((x0 - ox) / cell_m))), min(nx, int(math.ceil((x1 - ox) / cell_m)) + 1)
    j0, j1 = max(0, int(math.floor((y0 - oy) / cell_m))), min(ny, int(math.ceil((y1 - oy) / cell_m)) + 1)
    if i0 >= i1 or j0 >= j1:
        return grid
    X, Y = np.meshgrid(ox + (np.arange(i0, i1) + 0.5) * cell_m, oy + (np.arange(j0, j1) + 0.5) * cell_m)
    grid[j0:j1, i0:i1][shapely.contains_xy(geometry, X, Y)] = OCCUPIED
    return grid


def occupancy(geometry, robot_xy, goal_xy, cell_m: float, pad_m: float, stamp, frame_id: str,
              max_cells_per_side: int = MAX_CELLS_PER_SIDE) -> OccupancyGrid:
    """The obstacle map as nav_msgs/OccupancyGrid in frame_id (the planner's world frame), cells of
    cell_m over grid_window's box (at most max_cells_per_side a side). 100: the map's geometry covers
    the cell's centre. 0 ("free") is every other cell: the map keeps no record of the floor the views
    showed (a view's floor only clears what the map held there, ObstacleMap.add_view), so free means
    "no obstacle on the map", seen or not; no cell is -1 (unknown)."""
    origin, shape = grid_window(geometry, robot_xy, goal_xy, cell_m, pad_m, max_cells_per_side)
    grid = rasterise(geometry, origin, shape, cell_m)
    m = OccupancyGrid()
    m.header.stamp, m.header.frame_id = stamp, frame_id
    m.info.map_load_time = stamp
    m.info.resolution = float(cell_m)
    m.info.width, m.info.height = shape
    m.info.origin.position.x, m.info.origin.position.y = float(origin[0]), float(origin[1])
    m.info.origin.orientation.w = 1.0
    m.data = grid.ravel().tolist()
    return m


def local_grid(local_map, stamp, frame_id: str) -> OccupancyGrid:
    """The layered planner's rolling grid as nav_msgs/OccupancyGrid in frame_id: 100 occupied, 0 seen
    as floor, -1 unknown (LocalMap.grid(), [i, j] = x, y, transposed to the message's rows of y)."""
    m = OccupancyGrid()
    m.header.stamp, m.header.frame_id = stamp, frame_id
    m.info.map_load_time = stamp
    m.info.resolution = float(local_map.params.cell_m)
    m.info.origin.orientation.w = 1.0
    if local_map.origin is None:
        return m
    grid = local_map.grid()
    half = 0.5 * local_map.params.cell_m                   # origin: the corner of cell (0, 0), not its centre
    m.info.width, m.info.height = grid.shape
    m.info.origin.position.x = float(local_map.origin[0] - half)
    m.info.origin.position.y = float(local_map.origin[1] - half)
    m.data = grid.T.ravel().tolist()
    return m


def traversability_mask(ground: np.ndarray, stamp, frame_id: str):
    """A replan's traversability image (H, W) bool -> sensor_msgs/Image mono8: 255 ground, 0 not."""
    return to_image(np.where(np.asarray(ground, bool), 255, 0).astype(np.uint8), "mono8", stamp, frame_id)


def world_markers(world, stamp, frame_id: str) -> MarkerArray:
    """A world's obstacles (cylinders, boxes at their height, standing on the floor) and its goal
    disc (a flat cylinder of goal_radius_m) in frame_id, after a DELETEALL of what was shown before."""
    out = MarkerArray()
    clear = Marker()
    clear.header.stamp, clear.header.frame_id = stamp, frame_id
    clear.action = Marker.DELETEALL
    out.markers.append(clear)
    for i, ob in enumerate(world.obstacles):
        m = _marker(frame_id, stamp, "world_obstacles", i, Marker.CYLINDER if ob.kind == "cylinder" else Marker.CUBE)
        m.pose.position.x, m.pose.position.y, m.pose.position.z = ob.x_m, ob.y_m, 0.5 * ob.top_m
        if ob.kind == "cylinder":
            m.scale.x = m.scale.y = 2.0 * ob.radius_m
        else:
            m.scale.x, m.scale.y = ob.size_m[0], ob.size_m[1]
            yaw = math.radians(ob.yaw_deg)
            m.pose.orientation = Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
        m.scale.z = ob.top_m
        m.color = OBSTACLE_COLOUR
        out.markers.append(m)
    g = _marker(frame_id, stamp, "world_goal", 0, Marker.CYLINDER)
    g.pose.position.x, g.pose.position.y, g.pose.position.z = world.goal[0], world.goal[1], 0.5 * GOAL_HEIGHT_M
    g.scale.x = g.scale.y = 2.0 * world.goal_radius_m
    g.scale.z = GOAL_HEIGHT_M
    g.color = GOAL_COLOUR
    out.markers.append(g)
    return out



CONTACT_COLOUR = ColorRGBA(0.9, 0.1, 0.9, 0.9)
CONTACT_SIZE_M = 0.04


def contact_marker(episode, index: int, stamp, frame_id: str) -> Marker:
    """One contact episode of the simulated robot with an obstacle (sim/collisions.ContactEpisode): a
    sphere at the touching link's centre, its text "LINK touched OBSTACLE" (runs/nav_record.py reads
    it back from a run's bag)."""
    m = _marker(frame_id, stamp, "contacts", index, Marker.SPHERE)
    m.pose.position.x, m.pose.position.y, m.pose.position.z = episode.x_m, episode.y_m, CONTACT_SIZE_M / 2
    m.scale.x = m.scale.y = m.scale.z = CONTACT_SIZE_M
    m.color = CONTACT_COLOUR
    m.text = f"{episode.link}{CONTACT_TEXT}{episode.obstacle}"
    return m


def contact_markers(episodes, stamp, frame_id: str) -> MarkerArray:
    """Every contact episode so far, one contact_marker each (ids = the episodes' order): a latched array
    shows rviz, and anything started after a contact, all of them (a lone Marker reaches only those
    subscribed when it is sent)."""
    return MarkerArray(markers=[contact_marker(e, i, stamp, frame_id) for i, e in enumerate(episodes)])
