"""Support polygons (paper II, III.B) and the ZMP's distance to their edges, with shapely.

U is the convex hull of a base's ground contacts. A `Support` is the polygon the planner keeps the
ZMP in: U itself, or U shrunk by a safety margin (the servos sag and the contacts are not points),
or U ∩ U' before a transfer (eq. 1).
"""
import numpy as np
import shapely
from shapely.geometry import MultiPoint, Point, Polygon


def convex_hull(points_xy) -> Polygon:
    """The convex hull of (k, 2) points; an empty polygon when they span no area."""
    hull = MultiPoint([tuple(p) for p in np.asarray(points_xy, float)]).convex_hull
    return hull if isinstance(hull, Polygon) and hull.area > 0 else Polygon()


def polygon_coords(poly: Polygon) -> list:
    """[[x, y], ...] of a polygon's exterior, counter-clockwise, not closed (empty: [])."""
    if poly.is_empty:
        return []
    ring = shapely.geometry.polygon.orient(poly, 1.0).exterior.coords[:-1]
    return [[float(x), float(y)] for x, y in ring]


class Support:
    """A support region for the ZMP: signed edge distance, membership."""

    def __init__(self, polygon: Polygon):
        self.polygon = polygon if polygon.is_valid else polygon.buffer(0)
        if not self.polygon.is_empty:
            shapely.prepare(self.polygon)
        self._boundary = self.polygon.boundary

    @classmethod
    def of(cls, contacts_xy, margin_m: float = 0.0, other=None) -> "Support":
        """Hull of contacts_xy shrunk by margin_m, intersected with `other` (a Support) if given."""
        poly = convex_hull(contacts_xy)
        if margin_m > 0 and not poly.is_empty:
            poly = poly.buffer(-margin_m, join_style="mitre")
        if other is not None:
            poly = poly.intersection(other.polygon)
        if not isinstance(poly, Polygon):
            poly = Polygon()
        return cls(poly)

    @property
    def empty(self) -> bool:
        return self.polygon.is_empty or self.polygon.area <= 0

    def signed_distance(self, points_xy) -> np.ndarray:
        """l of eq. 13 for each point: distance to the nearest edge, > 0 inside, < 0 outside."""
        pts = np.atleast_2d(np.asarray(points_xy, float))
        if self.empty:
            return np.full(len(pts), -np.inf)
        d = shapely.distance(self._boundary, shapely.points(pts))
        inside = shapely.contains_xy(self.polygon, pts[:, 0], pts[:, 1])
        return np.where(inside, d, -d)

    def contains(self, points_xy) -> np.ndarray:
        return self.signed_distance(points_xy) > 0

    def contains_point(self, xy) -> bool:
        return (not self.empty) and self.polygon.contains(Point(float(xy[0]), float(xy[1])))
