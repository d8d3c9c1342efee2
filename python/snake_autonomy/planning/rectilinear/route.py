"""A coarse route to the goal on the obstacle map, ROS-free: the cost to go the
perception-space planner's goal bias steers by, instead of the distance to the goal.

The paper's planner is local: its arcs see 1.2 m, and the goal bias (sampler.goal_tie_m) pulled them
straight at the goal. Where obstacles stand closer together than the checked footprint (2 x
sampler.body_clearance_m) the robot drove into the funnel between them, found no free arc, and
touched while backing off and turning in place (world 6, even with every obstacle known).
A route on a grid over the map (scipy.sparse.csgraph.dijkstra from the goal, 8-connected) keeps the
robot out of such funnels from the moment the views show them: the goal bias takes the arc whose
free prefix reaches the least cost to go (sampler.py). Cells within inflation_m of an obstacle (the
planner passes half its checked footprint) cost inflated_cost per metre (passable, so that a route
always exists, even from inside the inflation), cells inside one blocked_cost; unknown floor is free
(optimistic, as the arcs' known_free_m beyond their first metres).

The grid covers the start-goal box grown by pad_m; its cells are bounded (map.route_max_cells):
a goal 150 m away once took 3.85 GB here. grid_shape refuses a larger grid, naming its extent,
before anything is allocated; the simulator asks it before a run starts.
"""
import numpy as np
import shapely
from scipy.sparse.csgraph import dijkstra

from .grid_route import grid_graph


MAX_CELLS = 1_000_000   # map.route_max_cells' default (MapParams)


class RouteGridError(ValueError):
    """The route's grid would exceed its bound of cells."""


def grid_shape(start_xy, goal_xy, cell_m: float, pad_m: float, max_cells: int = MAX_CELLS):
    """(lo, (nx, ny)): the corner and the cells of the grid over the start-goal box grown by pad_m;
    RouteGridError naming the extent when it has more than max_cells cells (nothing allocated)."""
    start, goal = np.asarray(start_xy, float), np.asarray(goal_xy, float)
    lo = np.minimum(start, goal) - pad_m
    hi = np.maximum(start, goal) + pad_m
    extent = hi - lo
    if not np.all(np.isfinite(extent)):
        raise RouteGridError(f"route grid: start {start.tolist()} or goal {goal.tolist()} is not finite")
    nx, ny = (int(v) for v in np.ceil(extent / cell_m) + 1)
    if nx * ny > max_cells:
        raise RouteGridError(
            f"route grid: {extent[0]:.1f} m x {extent[1]:.1f} m (start {_xy(start)} to goal {_xy(goal)}, "
            f"padded {pad_m:g} m) at {cell_m:g} m cells is {nx} x {ny} = {nx * ny} cells, more than "
            f"map.route_max_cells = {max_cells}: a nearer goal, larger map.cell_m or map.route: false")
    return lo, (nx, ny)


def _xy(p) -> str:
    return f"({p[0]:.1f}, {p[1]:.1f})"


class Route:
    def __init__(self, cell_m: float = 0.04, inflation_m: float = 0.25, pad_m: float = 1.0,
                 inflated_cost: float = 20.0, blocked_cost: float = 1000.0, max_cells: int = MAX_CELLS):
        self.cell_m, self.inflation_m, self.pad_m, self.max_cells = cell_m, inflation_m, pad_m, max_cells
        self.inflated_cost, self.blocked_cost = inflated_cost, blocked_cost
        self.path = None                       # (K, 2) world points of the last route, robot to goal
        self._field = None
        self._goal = None

    def update(self, geometry, start_xy, goal_xy) -> None:
        """The cost-to-go field to goal_xy around `geometry` (a shapely geometry in the world frame,
        or None / empty: straight lines) and the route from start_xy; RouteGridError when its grid
        would have more than max_cells cells."""
        start, goal = np.asarray(start_xy, float), np.asarray(goal_xy, float)
        self._goal = goal
        if geometry is None or geometry.is_empty:
            self._field = None
            self.path = np.array([start, goal])
            return
        lo, (nx, ny) = grid_shape(start, goal, self.cell_m, self.pad_m, self.max_cells)
        xs, ys = lo[0] + self.cell_m * np.arange(nx), lo[1] + self.cell_m * np.arange(ny)
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        cost = np.ones((nx, ny))
        near = geometry.buffer(self.inflation_m, 8)
        cost[shapely.contains_xy(near, X, Y)] = self.inflated_cost
        cost[shapely.contains_xy(geometry, X, Y)] = self.blocked_cost
        self._lo, self._shape = lo, (nx, ny)
        g, s = self._cell(goal), self._cell(start)
        dist, pred = dijkstra(grid_graph(cost, self.cell_m), directed=False, indices=g,
                              return_predecessors=True)
        self._field = dist.reshape(nx, ny)
        cells = [s]
        while cells[-1] != g and pred[cells[-1]] >= 0:
            cells.append(int(pred[cells[-1]]))
        pts = np.column_stack([xs[np.array(cells) // ny], ys[np.array(cells) % ny]])
        self.path = np.vstack([start, pts[1:-1], goal]) if len(pts) > 2 else np.array([start, goal])

    def _indices(self, xy: np.ndarray):
        """(M, 2) world points -> the (i, j) of their nearest grid cells, clipped to the grid."""
        nx, ny = self._shape
        ij = np.rint((np.asarray(xy, float).reshape(-1, 2) - self._lo) / self.cell_m).astype(np.int64)
        return np.clip(ij[:, 0], 0, nx - 1), np.clip(ij[:, 1], 0, ny - 1)

    def _cell(self, p) -> int:
        i, j = self._indices(p)
        return int(i[0]) * self._shape[1] + int(j[0])

    def cost_to_go(self, xy: np.ndarray) -> np.ndarray:
        """(M, 2) world points -> (M,) the route's cost from each to the goal (metres, inflated
        cells counted inflated_cost times); off the grid: its nearest cell's plus the way there."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self._field is None:
            return np.hypot(xy[:, 0] - self._goal[0], xy[:, 1] - self._goal[1])
        i, j = self._indices(xy)
        snapped = self._lo + self.cell_m * np.column_stack([i, j])
        return self._field[i, j] + np.hypot(*(xy - snapped).T)

