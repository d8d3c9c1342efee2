"""The local map: one rolling occupancy grid of what the head camera's views showed, ROS-free.

Every replan's traversability image (depth or monocular alike: a boolean ground mask) is laid on the
floor through the camera's pose: the ground pixels are free observations of the cells they fall in,
the obstacle faces (where a column's ground region, counted from the image's bottom row, ends below
a non-ground pixel the sensor measured: not where its view ends) occupied observations of the cells
from the face to `face_depth_m` behind it along the ray (a face tells where an obstacle's near side
is; what lies behind it stays unknown until a view shows it). Each cell keeps the log-odds of being
occupied (the occupancy-grid update of Thrun et al., Probabilistic Robotics ch. 9, as costmap_2d's
obstacle layer and OctoMap keep it), clamped so that later views can clear a cell a misjudged view
marked: a cell is occupied above `occupied_log_odds`, free below `free_log_odds`, unknown between.

The grid is a window of `size_m` around the robot, rolled (whole cells, the cells that enter are
unknown) when the camera moves more than a quarter of the window from its centre. The checks ask it
for each point's distance to the nearest occupied cell (scipy's Euclidean distance transform,
computed once per update) and whether a point was seen free; grid_route.py plans the route on it.
numpy + scipy only: costmap_2d and grid_map are C++ ROS libraries, and the planner must run without
ROS in the batch simulator.
"""
import functools
import math
from dataclasses import dataclass
from typing import List, Tuple

import numpy as np
from scipy.ndimage import distance_transform_edt

from .collision_check import floor_hits

UNKNOWN, FREE, OCCUPIED = -1, 0, 100       # nav_msgs/OccupancyGrid values


@dataclass(frozen=True)
class LocalMapParams:
    """config/nav.yaml `local_map:`; the defaults are its values."""
    cell_m: float = 0.04
    size_m: float = 8.0               # the window's side (the route is planned inside it)
    free_range_m: float = 1.5         # ground pixels further than this from the camera are not taken
    face_range_m: float = 0.8         # faces further than this are not taken (a pixel row spans 3.6 cm
                                      # of floor at 1 m with the camera 4.6 cm up)
    face_depth_m: float = 0.1         # a face marks the cells this far behind it along its ray
    edge_px: int = 6                  # a face is placed this many rows below the ground region's edge
    stride_px: int = 4                # every 4th row and column of the image
    hit_log_odds: float = 0.85        # an occupied observation (p 0.7)
    miss_log_odds: float = 0.4        # a free observation (p 0.4): about two views clear one mark
    min_log_odds: float = -2.0
    max_log_odds: float = 3.5
    occupied_log_odds: float = 0.6    # above: occupied
    free_log_odds: float = -0.3       # below: free (seen as floor)
    blind_m: float = 0.15             # the head's first metres need not be seen free: the camera's near
                                      # field (it sees the floor from about 0.06 m ahead of the head)
    start_free_m: float = 0.25        # the robot is placed with this much free floor round its body: known
                                      # free at the first view (the camera has not seen beside or behind it)
    view_end_m: float = 0.3           # a ground region ending at pixels the sensor did not measure (a depth
                                      # camera's grazing floor, its range) further than this from the camera
                                      # ends the view, no face; nearer, a face (an obstacle nearer than the
                                      # camera's minimum range has no depth)

    def validate(self) -> List[str]:
        p = []
        for key in ("cell_m", "size_m", "free_range_m", "face_range_m", "hit_log_odds", "miss_log_odds",
                    "max_log_odds", "blind_m", "view_end_m"):
            if not getattr(self, key) > 0:
                p.append(f"{key}: must be > 0, got {getattr(self, key)}")
        for key in ("face_depth_m", "start_free_m"):
            if not getattr(self, key) >= 0:
                p.append(f"{key}: must be >= 0, got {getattr(self, key)}")
        for key in ("edge_px", "stride_px"):
            v = getattr(self, key)
            if not isinstance(v, int) or v < (1 if key == "stride_px" else 0):
                p.append(f"{key}: must be an integer >= {1 if key == 'stride_px' else 0}, got {v!r}")
        if not self.min_log_odds < self.free_log_odds < self.occupied_log_odds < self.max_log_odds:
            p.append("min_log_odds < free_log_odds < occupied_log_odds < max_log_odds must hold, got "
                     f"{self.min_log_odds}, {self.free_log_odds}, {self.occupied_log_odds}, {self.max_log_odds}")
        if self.cell_m > 0 and self.size_m / self.cell_m > 2000:
            p.append(f"size_m: {self.size_m} m at cell_m {self.cell_m} m is more than 2000 cells a side")
        return p


class LocalMap:
    def __init__(self, params: LocalMapParams = LocalMapParams()):
        self.params = params
        self.n = int(math.ceil(params.size_m / params.cell_m))
        self.log_odds = np.zeros((self.n, self.n), np.float32)     # [i, j]: x, y
        self.origin = None                  # world (x, y) of cell (0, 0)'s centre; None: not placed yet
        self.swept = np.zeros((self.n, self.n), bool)               # cells the body has lain on
        self._dist = self._unknown_dist = None
        self._cleared_key, self._cleared = None, None     # distance_clearing's field and the cells it cleared
        self._known_key, self._known_occ = None, None     # know(): the window it was computed for, its cells
        self.updates = 0

    # --- placing the window ---
    def _place(self, centre_xy) -> None:
        c = np.asarray(centre_xy, float)
        half = 0.5 * (self.n - 1) * self.params.cell_m
        if self.origin is None:
            self.origin = c - half
            return
        shift = np.rint((c - half - self.origin) / self.params.cell_m).astype(int)
        if np.all(np.abs(shift) * self.params.cell_m <= 0.25 * self.params.size_m):
            return
        new = np.zeros_like(self.log_odds)
        n = self.n
        si, sj = int(shift[0]), int(shift[1])
        src_i, dst_i = slice(max(0, si), min(n, n + si)), slice(max(0, -si), min(n, n - si))
        src_j, dst_j = slice(max(0, sj), min(n, n + sj)), slice(max(0, -sj), min(n, n - sj))
        new[dst_i, dst_j] = self.log_odds[src_i, src_j]
        swept = np.zeros_like(self.swept)
        swept[dst_i, dst_j] = self.swept[src_i, src_j]
        self.log_odds, self.swept = new, swept
        self.origin = self.origin + shift * self.params.cell_m
        self._dist = self._unknown_dist = None

    def cells(self, xy: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, 2) world points -> their cells (i, j) and whether they lie in the window."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        n = self.n
        i = np.rint((xy[:, 0] - self.origin[0]) / self.params.cell_m).astype(np.int64)
        j = np.rint((xy[:, 1] - self.origin[1]) / self.params.cell_m).astype(np.int64)
        inside = (i >= 0) & (i < n) & (j >= 0) & (j < n)
        return np.minimum(np.maximum(i, 0), n - 1), np.minimum(np.maximum(j, 0), n - 1), inside

    def centres(self) -> Tuple[np.ndarray, np.ndarray]:
        """The cells' centres' world x (n,) and y (n,)."""
        a = np.arange(self.n) * self.params.cell_m
        return self.origin[0] + a, self.origin[1] + a

    # --- the update ---
    def add_view(self, ground: np.ndarray, K: np.ndarray, T_world_camera: np.ndarray, unknown=None) -> None:
        """One traversability image (True = ground) seen from T_world_camera (the floor is z = 0).
        unknown: the pixels the sensor did not measure (ground_region.Traversability), or None: a column
        whose ground region ends at one further than view_end_m has no face (the view stopped there, no
        obstacle began)."""
        p = self.params
        T = np.asarray(T_world_camera, float)
        self._place(T[:2, 3])
        ground = np.asarray(ground, bool)
        h, w = ground.shape
        rows, cols = np.arange(h - 1, -1, -p.stride_px), np.arange(0, w, p.stride_px)
        g = ground[np.ix_(rows, cols)]
        # free: the sampled ground pixels on the floor within free_range_m
        r_idx, c_idx = np.nonzero(g)
        free_xy, _ = self._on_floor(cols[c_idx], rows[r_idx], K, T, p.free_range_m)
        # faces: per column, the top of the ground region that starts at the bottom row
        gc = ground[:, cols]
        run = np.where(gc.all(axis=0), h, np.argmin(gc[::-1], axis=0))      # ground rows from the bottom
        has_face = run < h
        if unknown is not None:          # the pixel above the region's top unmeasured: the view's end there
            ends = has_face & np.asarray(unknown, bool)[np.clip(h - 1 - run, 0, h - 1), cols]
            reach, _, down = floor_hits(cols[ends], h - run[ends] - 0.5, K, T)
            has_face[np.flatnonzero(ends)[~down | (reach > p.view_end_m)]] = False
        face_row = np.minimum(h - run - 0.5 + p.edge_px, h - 0.5)[has_face]
        faces, dirs = self._on_floor(cols[has_face], face_row, K, T, p.face_range_m)
        steps = np.arange(0.0, p.face_depth_m + 1e-9, 0.5 * p.cell_m)
        occ_xy = (faces[:, None, :] + steps[None, :, None] * dirs[:, None, :]).reshape(-1, 2)
        occ = self._cell_ids(occ_xy)
        free = np.setdiff1d(self._cell_ids(free_xy), occ, assume_unique=True)
        lo = self.log_odds.ravel()                       # a view of the grid
        lo[free] = np.maximum(lo[free] - p.miss_log_odds, p.min_log_odds)
        lo[occ] = np.minimum(lo[occ] + p.hit_log_odds, p.max_log_odds)
        self._dist = self._unknown_dist = None
        self.updates += 1

    def mark_body(self, xy: np.ndarray, radius_m: float) -> None:
        """The cells within radius_m of the body's stations xy (world, (M, 2)) are known free: the body lies
        there. Kept apart from the log-odds: a modelled body a few centimetres off the real one must not
        clear an obstacle's mark, only make its surroundings known."""
        if self.origin is None:
            return
        di, dj = self._disc(int(np.floor(radius_m / self.params.cell_m)))
        i, j, inside = self.cells(xy)
        ii = (i[inside, None] + di[None, :]).ravel()
        jj = (j[inside, None] + dj[None, :]).ravel()
        ok = (ii >= 0) & (ii < self.n) & (jj >= 0) & (jj < self.n)
        self.swept[ii[ok], jj[ok]] = True
        self._unknown_dist = None

    def know(self, world, T_world_camera: np.ndarray) -> None:
        """The simulator's diagnostic (map.source truth), in place of add_view: the window placed as a view
        from T_world_camera places it, and every cell of it as the world has it, occupied where an
        obstacle covers its centre's half cell, free elsewhere. world: anything with distance((M, 2)
        points) -> (M,) metres to the nearest obstacle (obstacle_map.ObstacleMap.from_world). The cells
        are computed again only when the window rolls."""
        self._place(np.asarray(T_world_camera, float)[:2, 3])
        key = (float(self.origin[0]), float(self.origin[1]))
        if self._known_key != key:
            x, y = self.centres()
            X, Y = np.meshgrid(x, y, indexing="ij")
            d = np.asarray(world.distance(np.column_stack([X.ravel(), Y.ravel()]))).reshape(self.n, self.n)
            self._known_occ, self._known_key = d <= 0.5 * self.params.cell_m, key
        p = self.params
        self.log_odds[:] = np.where(self._known_occ, p.max_log_odds, p.min_log_odds)
        self._dist = self._unknown_dist = None
        self.updates += 1

    @staticmethod
    @functools.lru_cache(maxsize=8)
    def _disc(r: int):
        """The cell offsets (di, dj) within r cells of a cell (a handful of radii per run: cached)."""
        a = np.arange(-r, r + 1)
        di, dj = np.meshgrid(a, a, indexing="ij")
        disc = di ** 2 + dj ** 2 <= r * r
        return di[disc], dj[disc]

    def _cell_ids(self, xy: np.ndarray) -> np.ndarray:
        """The distinct flat indices of the window's cells the points fall in (points outside: none)."""
        if not len(xy):
            return np.zeros(0, np.int64)
        i, j, inside = self.cells(xy)
        return np.unique(i[inside] * self.n + j[inside])

    @staticmethod
    def _on_floor(cols, rows, K, T, max_range_m):
        """(floor points (M, 2), their rays' directions on the floor (M, 2)) of the pixels whose ray meets
        the floor within max_range_m of the camera."""
        reach, dirs, down = floor_hits(cols, rows, K, T)
        keep = down & (reach <= max_range_m)
        return T[:2, 3] + reach[keep, None] * dirs[keep], dirs[keep]

    # --- queries ---
    def occupied(self) -> np.ndarray:
        return self.log_odds > self.params.occupied_log_odds

    def free(self) -> np.ndarray:
        return self.log_odds < self.params.free_log_odds

    def distance_field(self) -> np.ndarray:
        """(n, n) each cell's distance (m) to the nearest occupied cell (inf: none in the window)."""
        if self._dist is None:
            occ = self.occupied()
            if occ.any():
                self._dist = distance_transform_edt(~occ) * self.params.cell_m
            else:
                self._dist = np.full(occ.shape, np.inf)
        return self._dist

    def distance(self, xy: np.ndarray) -> np.ndarray:
        """(M, 2) world points -> (M,) distance to the nearest occupied cell (inf off the window or with
        no map yet); the cell's centre stands for the point, less half a cell."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self.origin is None:
            return np.full(len(xy), np.inf)
        i, j, inside = self.cells(xy)
        d = self.distance_field()[i, j] - 0.5 * self.params.cell_m
        return np.where(inside, np.maximum(d, 0.0), np.inf)

    def distance_clearing(self, xy: np.ndarray, under_xy: np.ndarray, radius_m: float) -> np.ndarray:
        """distance() on the map without the occupied cells within radius_m of the points under_xy (a
        body the map puts inside an obstacle is a misplaced body or a misjudged cell: those cells do
        not count for it). The field is kept for the same cells cleared."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        i, j, inside = self.cells(np.asarray(under_xy, float).reshape(-1, 2))
        key = (self.updates, radius_m, tuple(sorted(set(zip(i[inside].tolist(), j[inside].tolist())))))
        if self._cleared_key != key:
            occ = self.occupied()
            r = int(np.ceil(radius_m / self.params.cell_m))
            for a, b in key[2]:
                occ[max(0, a - r):a + r + 1, max(0, b - r):b + r + 1] = False
            self._cleared = (distance_transform_edt(~occ) * self.params.cell_m if occ.any()
                             else np.full(occ.shape, np.inf))
            self._cleared_key = key
        i, j, inside = self.cells(xy)
        d = self._cleared[i, j] - 0.5 * self.params.cell_m
        return np.where(inside, np.maximum(d, 0.0), np.inf)

    def seen_free(self, xy: np.ndarray) -> np.ndarray:
        """(M, 2) world points -> (M,) whether a view showed their cell as floor, or the body lay on it and no
        view has marked it."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self.origin is None:
            return np.zeros(len(xy), bool)
        i, j, inside = self.cells(xy)
        return inside & (self.free()[i, j] | (self.swept[i, j] & (self.log_odds[i, j] <= 0.0)))

    def unknown_distance(self, xy: np.ndarray) -> np.ndarray:
        """(M, 2) world points -> (M,) distance to the nearest unknown cell (neither seen nor lain on; 0
        off the window), less half a cell."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self.origin is None:
            return np.zeros(len(xy))
        if self._unknown_dist is None:
            known = self.free() | self.occupied() | self.swept
            self._unknown_dist = (distance_transform_edt(known) * self.params.cell_m if not known.all()
                                  else np.full(known.shape, np.inf))
        i, j, inside = self.cells(xy)
        d = self._unknown_dist[i, j] - 0.5 * self.params.cell_m
        return np.where(inside, np.maximum(d, 0.0), 0.0)

    def geometry(self):
        """The occupied cells as one shapely geometry in the world frame (empty: none, or not placed):
        what a run's top view draws."""
        from shapely.geometry import box
        from shapely.ops import unary_union
        if self.origin is None:
            return unary_union([])
        xs, ys = self.centres()
        h = 0.5 * self.params.cell_m
        return unary_union([box(xs[i] - h, ys[j] - h, xs[i] + h, ys[j] + h) for i, j in np.argwhere(self.occupied())])

    def grid(self) -> np.ndarray:
        """(n, n) int8 OCCUPIED / FREE / UNKNOWN, [i, j] = x, y (nav_msgs/OccupancyGrid's values)."""
        out = np.full(self.log_odds.shape, UNKNOWN, np.int8)
        out[self.free()] = FREE
        out[self.occupied()] = OCCUPIED
        return out
