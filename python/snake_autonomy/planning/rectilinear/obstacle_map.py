"""A world-frame map of the obstacles the views showed, ROS-free.

The checks judge a point the current image shows by the image (the paper's perception space). A
point it does not show (beside the body, behind the camera) was until now looked up in the earlier
views only, and a side of an obstacle no view had shown counted as floor (the side of a
cylinder link 2 touched had been shown by none of the 30 views). An ObstacleMap answers for those
hidden points (collision_check.py hidden_obstacles), and the route (route.py) plans on it.

Sources (config/nav.yaml map.source):
- faces: each view's faces, where its ground region ends below a non-ground pixel, on the floor and
  within max_range_m, each grown into a disc of prior_radius_m behind it along the view's ray (a
  prior on the unseen extent: a cylinder's face tells where its near side is, not how far it reaches
  to the sides); the floor a later view shows clears the map there first (view_on_floor,
  add_view), so a far edge the depth test once marked unsure does not stay an obstacle. Two other
  priors were measured on COBRA and dropped: the disc along the surface's normal fitted to the
  view's neighbouring faces (with depth it lost as many runs on one set of seeds as it gained on
  another), and the floor behind each run of faces between the run's outermost rays;
- truth: the simulated world's obstacles as they are (a diagnostic upper bound: what a perfect map
  gives the planner; simulation only).
Geometry is shapely's (a prepared polygon, contains_xy).
"""
from dataclasses import dataclass
from typing import Iterable, List

import numpy as np
import shapely
from shapely.geometry import Point, Polygon

from .collision_check import floor_hits

MAP_SOURCES = ("none", "faces", "truth")


@dataclass(frozen=True)
class MapParams:
    """config/nav.yaml `map:`; the defaults are its values."""
    source: str = "faces"         # none | faces (the views' obstacle faces with the prior) | truth (the
                                  # simulated world's obstacles: a diagnostic, simulation only)
    prior_radius_m: float = 0.1   # faces: each face point is the near side of a disc of this radius
    max_range_m: float = 0.8      # faces further from the camera on the floor are not taken: with the
                                  # camera 4.6 cm above the floor a pixel row spans 3.6 cm of floor at
                                  # 1 m (1.3 cm at 0.6 m), and the cells' edges were 0.1-0.3 m off there
    edge_px: int = 6              # a face is placed this many rows below the ground region's top edge
                                  # (nearer): a cell at the edge is ground when half of it is (README
                                  # depth's faces lay a median 2-7 cm behind the obstacle's
                                  # surface at 0, 1-3 cm in front at 4-8; mono's 20 px cells alike)
    column_step_px: int = 4       # faces: every 4th image column
    route: bool = True            # the goal bias steers by the route's cost to go (route.py)
    cell_m: float = 0.04          # route grid
    inflated_cost: float = 20.0   # route: a metre within half the checked footprint (the arcs' reach,
                                  # sampler.body_clearance_m) of an obstacle costs this many
    pad_m: float = 1.0            # route grid: the start-goal box grown by this
    route_max_cells: int = 1_000_000   # route grid: at most this many cells (about 250 bytes and 0.8 us
                                  # a cell per replan: 1e6 = 40 m x 40 m at 4 cm, 250 MB); a larger
                                  # start-goal box is refused naming its extent (route.grid_shape)
    priors_off_own_floor: bool = True    # a view's prior discs are not laid on the floor
                                  # the same view shows (ObstacleMap.add_view)

    def validate(self) -> List[str]:
        p = []
        if self.source not in MAP_SOURCES:
            p.append(f"source: expected one of {', '.join(MAP_SOURCES)}, got {self.source!r}")
        for key in ("prior_radius_m", "max_range_m", "cell_m", "pad_m"):
            if not getattr(self, key) > 0:
                p.append(f"{key}: must be > 0, got {getattr(self, key)}")
        if (not isinstance(self.route_max_cells, int) or isinstance(self.route_max_cells, bool)
                or not 1 <= self.route_max_cells <= 10_000_000):
            p.append(f"route_max_cells: must be an integer in 1..10000000, got {self.route_max_cells!r}")
        if not self.inflated_cost >= 1:
            p.append(f"inflated_cost: must be >= 1, got {self.inflated_cost}")
        if not isinstance(self.edge_px, int) or self.edge_px < 0:
            p.append(f"edge_px: must be an integer >= 0, got {self.edge_px!r}")
        if not isinstance(self.column_step_px, int) or self.column_step_px < 1:
            p.append(f"column_step_px: must be an integer >= 1, got {self.column_step_px!r}")
        if not isinstance(self.priors_off_own_floor, bool):
            p.append(f"priors_off_own_floor: must be true or false, got {self.priors_off_own_floor!r}")
        if not isinstance(self.route, bool):
            p.append(f"route: must be true or false, got {self.route!r}")
        if self.route and self.source == "none":
            p.append("route: true needs a map (source faces or truth), got source none")
        return p


def view_on_floor(ground: np.ndarray, K: np.ndarray, T_world_camera: np.ndarray, max_range_m: float,
                  column_step_px: int = 1, edge_px: int = 0):
    """What a traversability image shows on the floor (z = 0 of the world frame), per column (every
    column_step_px): its ground region from the bottom row up to edge_px rows below the region's top
    edge, at most max_range_m from the camera. -> (faces (M, 2), their rays' unit directions on the
    floor (M, 2), the floor seen (a shapely polygon)). A face is that edge where a non-ground pixel
    lies above it, nearer than max_range_m."""
    ground = np.asarray(ground, bool)
    h, w = ground.shape
    cols = np.arange(0, w, column_step_px)
    g = ground[:, cols]
    has = g.any(axis=0)
    top = np.argmax(g, axis=0)
    edge_row = np.where(has, np.minimum(top - 0.5 + edge_px, h - 0.5), h - 0.5)
    T = np.asarray(T_world_camera, float)
    edge, rng, dirs, down = _on_floor(cols, edge_row, K, T, max_range_m)
    near, _, _, _ = _on_floor(cols, np.full(len(cols), h - 0.5), K, T, max_range_m)
    is_face = has & (top > 0) & down & (rng < max_range_m)
    floor = Polygon(np.vstack([near, edge[::-1]])).buffer(0)
    return edge[is_face], dirs[is_face], floor


def face_discs(faces_xy: np.ndarray, dirs: np.ndarray, radius_m: float):
    """The disc prior: each face grown into the disc of radius_m behind it along its ray; their
    union."""
    centres = np.asarray(faces_xy, float).reshape(-1, 2) + radius_m * np.asarray(dirs, float).reshape(-1, 2)
    return shapely.union_all(shapely.buffer(shapely.points(centres), radius_m, quad_segs=4))


def _on_floor(cols, rows, K, T, max_range_m):
    """Pixels -> (floor points (N, 2) at most max_range_m from the camera along their rays, that range,
    the rays' unit directions on the floor, whether the ray meets the floor at all)."""
    reach, dirs, down = floor_hits(cols, rows, K, T)
    rng = np.minimum(reach, max_range_m)
    return T[:2, 3] + rng[:, None] * dirs, reach, dirs, down


class ObstacleMap:
    def __init__(self, geometry=None):
        self._geom = Polygon() if geometry is None else geometry
        self._prepared = False

    def add_view(self, faces_xy: np.ndarray, dirs: np.ndarray, floor, prior_radius_m: float,
                 priors_off_own_floor: bool = False) -> None:
        """One view (view_on_floor): the floor it shows clears what the map held there (an older view's
        face behind which this one sees floor: a cylinder's prior where its side is not, a far edge
        the depth test marked unsure), then each face point is grown into the disc of
        prior_radius_m behind it along its ray. priors_off_own_floor (MapParams): the discs
        are not laid on floor this same view shows: a disc behind a cylinder's outermost face
        reaches prior_radius_m beyond the cylinder's side, onto floor the view shows beside it."""
        seen = floor is not None and not floor.is_empty
        geom = self._geom.difference(floor) if seen else self._geom
        faces_xy = np.asarray(faces_xy, float).reshape(-1, 2)
        prior = face_discs(faces_xy, dirs, prior_radius_m) if len(faces_xy) else None
        if prior is not None and not prior.is_empty:
            if priors_off_own_floor and seen:
                prior = prior.difference(floor)
            geom = shapely.union_all([geom, prior])
        self._geom = geom.simplify(0.002)
        self._prepared = False

    @classmethod
    def from_world(cls, obstacles: Iterable) -> "ObstacleMap":
        """world_file.Obstacle's (cylinders and boxes) as they are."""
        parts = []
        for ob in obstacles:
            if ob.kind == "cylinder":
                parts.append(Point(ob.x_m, ob.y_m).buffer(ob.radius_m, 32))
            else:
                parts.append(Polygon(ob.corners()))
        return cls(shapely.union_all(parts) if parts else None)

    def geometry(self):
        """The map's obstacles (a prepared shapely geometry; empty: none)."""
        if not self._prepared:
            shapely.prepare(self._geom)
            self._prepared = True
        return self._geom

    def distance(self, xy: np.ndarray) -> np.ndarray:
        """(M, 2) world points -> (M,) metres to the nearest obstacle of the map (0 inside; inf: none)."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if self.geometry().is_empty:
            return np.full(len(xy), np.inf)
        return shapely.distance(self.geometry(), shapely.points(xy))

    def blocked(self, xy: np.ndarray) -> np.ndarray:
        """(M, 2) world points -> (M,) bool: inside an obstacle of the map."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        if not len(xy) or self.geometry().is_empty:
            return np.zeros(len(xy), bool)
        return shapely.contains_xy(self.geometry(), xy[:, 0], xy[:, 1])
