"""The route to the goal on the local map, ROS-free: the cost to go the route critic scores by.

The arcs see 1.2 m; the goal may lie behind a cluster whose gaps are narrower than the body. The
route is the global planner's part in Nav2's split (NavFn: Dijkstra on the costmap): scipy's
Dijkstra from the goal over an 8-connected grid of the local map at `route_cell_m`, each cell's
cost 1 where the nearest occupied cell is at least `inflation_m` away (half the robot's checked
width), `inflated_cost` nearer, `lethal_cost` within `lethal_m` (passable, so that a route always
exists, even from inside an obstacle's inflation); unknown cells cost 1 (optimistic: what no view
showed is seen before the robot gets there). A goal outside the window is reached through the window
cell nearest to it, plus the straight line from there.
Dead ends (`mark`): the cells within `mark_radius_m` of a place the robot recovered at cost
`mark_cost` more per mark for the rest of the run, in the world frame: a way the map shows open but
the body cannot take grows dearer with every failure until another way is cheaper, as learning
real-time search (LRTA*) raises the estimate of the states it leaves.
"""
import functools
import math
import numpy as np
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import dijkstra


def grid_graph(cost: np.ndarray, cell_m: float):
    """8-connected grid, each edge its length times the mean cost of its two cells."""
    a, b, length, template, order = _edges(cost.shape, cell_m)
    flat = cost.ravel()
    w = (length * 0.5 * (flat[a] + flat[b]))[order]
    return csr_matrix((w, template.indices, template.indptr), shape=template.shape)


@functools.lru_cache(maxsize=4)
def _edges(shape, cell_m: float):
    """The grid's edges (from, to, length) and their CSR structure (the template, and the order of
    the edges in it), kept per grid shape: the route's grid keeps its shape."""
    nx, ny = shape
    ids = np.arange(nx * ny).reshape(nx, ny)
    rows, cols, lengths = [], [], []
    for dx, dy in ((1, 0), (0, 1), (1, 1), (1, -1)):
        a = ids[0:nx - dx, max(0, -dy):ny - max(0, dy)].ravel()
        rows.append(a)
        cols.append(ids[dx:nx, max(0, dy):ny + min(0, dy)].ravel())
        lengths.append(np.full(len(a), cell_m * math.hypot(dx, dy)))
    a, b = np.concatenate(rows), np.concatenate(cols)
    template = coo_matrix((np.arange(1.0, len(a) + 1.0), (a, b)), shape=(nx * ny, nx * ny)).tocsr()
    return a, b, np.concatenate(lengths), template, template.data.astype(np.int64) - 1


class GridRoute:
    def __init__(self, route_cell_m: float, inflation_m: float, lethal_m: float, inflated_cost: float = 20.0,
                 lethal_cost: float = 1000.0, mark_cost: float = 0.0, mark_radius_m: float = 0.3):
        self.route_cell_m, self.inflation_m, self.lethal_m = route_cell_m, inflation_m, lethal_m
        self.inflated_cost, self.lethal_cost = inflated_cost, lethal_cost
        self.mark_cost, self.mark_radius_m = mark_cost, mark_radius_m
        self.marks = np.zeros((0, 2))       # world points of the places marked, one row per mark
        self.path = None                    # (K, 2) world points, robot to goal, of the last update
        self._field = None

    def mark(self, xy) -> None:
        """The robot recovered at xy (world): the cells within mark_radius_m cost mark_cost more."""
        self.marks = np.vstack([self.marks, np.asarray(xy, float)[:2].reshape(1, 2)])

    def marks_near(self, xy) -> int:
        """How many marks lie within mark_radius_m of xy."""
        return int((np.hypot(*(self.marks - np.asarray(xy, float)[:2]).T) <= self.mark_radius_m).sum())

    def update(self, local_map, start_xy, goal_xy) -> None:
        """The cost-to-go field on the map's window to goal_xy, and the route from start_xy."""
        self._goal = np.asarray(goal_xy, float)
        start = np.asarray(start_xy, float)
        if local_map.origin is None:
            self._field, self.path = None, np.array([start, self._goal])
            return
        f = max(1, int(round(self.route_cell_m / local_map.params.cell_m)))
        dist = local_map.distance_field()
        n = (dist.shape[0] // f) * f
        d = dist[:n, :n].reshape(n // f, f, n // f, f).min(axis=(1, 3))     # the nearest in each block
        cost = np.where(d < self.lethal_m, self.lethal_cost, np.where(d < self.inflation_m, self.inflated_cost, 1.0))
        cell = f * local_map.params.cell_m
        self._lo = local_map.origin + 0.5 * (f - 1) * local_map.params.cell_m
        if self.mark_cost > 0 and len(self.marks):
            cost = cost + self.mark_cost * self._mark_counts(cost.shape, cell)
        self._cell, self._shape = cell, cost.shape
        g_idx = self._index(self._goal[None])[0]
        g_cell = self._lo + cell * np.array(g_idx)
        goal_gap = float(np.hypot(*(self._goal - g_cell)))     # goal outside the window: the way there
        ny = cost.shape[1]
        field, pred = dijkstra(grid_graph(cost, cell), directed=False, indices=g_idx[0] * ny + g_idx[1],
                               return_predecessors=True)
        self._field = field.reshape(cost.shape) + goal_gap
        s_idx = self._index(start[None])[0]
        cells = [s_idx[0] * ny + s_idx[1]]
        while pred[cells[-1]] >= 0:
            cells.append(int(pred[cells[-1]]))
        cells = np.array(cells)
        pts = self._lo + cell * np.column_stack([cells // ny, cells % ny])
        self.path = np.vstack([start, pts[1:], self._goal])

    def _mark_counts(self, shape, cell: float) -> np.ndarray:
        """(nx, ny) how many marks lie within mark_radius_m of each cell's centre. Only the marks
        within reach of the window count, each over the block of cells its disc covers: the cost
        stays that of the cells near marks however many the run has made."""
        counts = np.zeros(shape)
        r = self.mark_radius_m
        hi = self._lo + cell * (np.array(shape) - 1)
        inside = np.all((self.marks >= self._lo - r) & (self.marks <= hi + r), axis=1)
        for m in self.marks[inside]:
            i0, j0 = np.maximum(np.floor((m - r - self._lo) / cell).astype(int), 0)
            i1, j1 = np.minimum(np.ceil((m + r - self._lo) / cell).astype(int), np.array(shape) - 1)
            x = self._lo[0] + cell * np.arange(i0, i1 + 1)
            y = self._lo[1] + cell * np.arange(j0, j1 + 1)
            counts[i0:i1 + 1, j0:j1 + 1] += np.hypot(x[:, None] - m[0], y[None, :] - m[1]) <= r
        return counts

    def _index(self, xy: np.ndarray) -> np.ndarray:
        ij = np.rint((np.asarray(xy, float).reshape(-1, 2) - self._lo) / self._cell).astype(np.int64)
        return np.clip(ij, 0, np.array(self._shape) - 1)

    def cost_to_go(self, xy: np.ndarray) -> np.ndarray:
        """(M, 2) world points -> (M,) cost to the goal (metres, inflated cells counted inflated_cost
        times); straight-line distance without a field."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self._field is None:
            return np.hypot(xy[:, 0] - self._goal[0], xy[:, 1] - self._goal[1])
        ij = self._index(xy)
        snapped = self._lo + self._cell * ij
        return self._field[ij[:, 0], ij[:, 1]] + np.hypot(*(xy - snapped).T)
