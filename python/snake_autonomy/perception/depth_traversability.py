"""Traversability from a depth image (the D435i that COBRA carries): ground-plane fit + height.

1. The depth image's points (optical frame, subsampled) are fitted with a plane by RANSAC, seeded
   with the points of the image's lower part, where the floor is expected; the plane is refined by
   least squares on its inliers, then (refine_iterations) refitted to the points within
   three robust sigmas of its own residuals: an obstacle's foot lies within RANSAC's 3 mm band too,
   and the floor seen spans 0.1-0.2 m, so its points tilted the plane enough to fail the floor far
   off. A plane that is not roughly where the mount puts the floor (its height from the camera, its
   normal) is refused, and the mount's floor plane is used instead.
2. A pixel is ground when its depth is valid and matches the depth at which its ray meets the
   plane within depth_tolerance (relative). A relative test, not a height threshold: the camera of a
   snake sits a few centimetres above the floor, so the bottom 2 cm of an obstacle at distance D
   hide the floor out to 1.8 D from a camera 4.6 cm up; a 5 % depth tolerance bounds that error to
   5 % of the distance (heights under 5 % of the camera's). The traversable region is grown from the
   bottom of the image (perception/ground_region.py).
3. Pixels without depth (0: a real sensor's invalid pixels, below its minimum range, at edges,
   beyond its range) are unknown, neither ground nor obstacle: a cell is judged on the pixels that
   have depth (ground when min_fraction of them are), and a cell with fewer than
   min_measured_fraction of its pixels measured is unknown. Growing from the bottom, a run of
   unknown cells joins the region when the first measured cell above it is ground (the floor nearer
   than the sensor's minimum range at the image's bottom, a hole in the floor) and ends it
   otherwise (under an obstacle, or with nothing measured above). `classify` also returns the
   unknown cells it did not join (ground_region.Traversability): a region ending at one ends where
   the sensor stopped seeing (the floor's grazing angle beyond about 0.1 x camera height x focal:
   0.96 m for a camera 2.5 cm up at a 385 px focal), not at an obstacle's face.
"""
from dataclasses import dataclass
from typing import List, Optional, Tuple

import numpy as np

from .ground_region import Traversability, cell_counts, expand_cells, grow_from_bottom


MIN_LOWER_POINTS = 200    # fewer measured points in the image's lower two thirds: the fit takes the whole image's


@dataclass
class DepthTraversabilityParams:
    depth_tolerance: float = 0.05      # |depth / depth of the plane along the ray - 1| below: ground
    max_range_m: float = 4.0           # beyond (or no depth): not ground
    stride_px: int = 4                 # subsampling of the fit
    ransac_iterations: int = 60
    inlier_m: float = 0.003
    block_px: int = 8                  # cells of the grown region
    min_fraction: float = 0.5
    max_plane_tilt_deg: float = 20.0   # fitted normal vs the mount's expected normal
    max_height_error_m: float = 0.05   # fitted camera height vs the mount's
    refine_iterations: int = 3         # > 0: refit the plane this many times to the points within
                                       # a band of 3 robust sigmas of its residuals (at least refine_floor_m,
                                       # at most inlier_m); 0: one least-squares fit to RANSAC's inliers
    refine_floor_m: float = 0.0005     # the narrowest band (below it: the sensor's noise, not the plane)
    min_measured_fraction: float = 0.25  # a cell with fewer of its pixels having depth is unknown

    def validate(self) -> List[str]:
        p = [f"{key}: must be > 0, got {getattr(self, key)}"
             for key in ("depth_tolerance", "max_range_m", "inlier_m", "min_fraction", "max_plane_tilt_deg",
                         "max_height_error_m", "refine_floor_m") if not getattr(self, key) > 0]
        for key in ("min_fraction", "min_measured_fraction"):
            if not 0 < getattr(self, key) <= 1:
                p.append(f"{key}: must be in (0, 1], got {getattr(self, key)}")
        p += [f"{key}: must be an integer >= {low}, got {getattr(self, key)!r}"
              for key, low in (("stride_px", 1), ("ransac_iterations", 1), ("block_px", 1), ("refine_iterations", 0))
              if not isinstance(getattr(self, key), int) or getattr(self, key) < low]
        return p


def plane_from_mount(T_ground_camera: np.ndarray) -> Tuple[np.ndarray, float]:
    """The floor z = 0 of the ground frame in the optical frame: (n, d) with n.p + d = height."""
    R, t = T_ground_camera[:3, :3], T_ground_camera[:3, 3]
    n = R.T @ np.array([0.0, 0.0, 1.0])        # ground's up axis in the camera frame
    return n, float(t[2])                       # height of a camera-frame point p: n.p + t_z


def fit_ground_plane(points: np.ndarray, params: DepthTraversabilityParams,
                     rng: np.random.Generator) -> Optional[Tuple[np.ndarray, float, int]]:
    """RANSAC plane through (N, 3) points: (n, d, inliers) with n.p + d = 0 on the plane, n
    oriented towards the camera (d > 0); None when fewer than 3 points."""
    if len(points) < 3:
        return None
    best, best_count = None, -1
    for _ in range(params.ransac_iterations):
        a, b, c = points[rng.choice(len(points), 3, replace=False)]
        n = np.cross(b - a, c - a)
        norm = np.linalg.norm(n)
        if norm < 1e-9:
            continue
        n /= norm
        d = -float(n @ a)
        count = int(np.count_nonzero(np.abs(points @ n + d) < params.inlier_m))
        if count > best_count:
            best, best_count = (n, d), count
    if best is None:
        return None
    n, d = best
    inl = points[np.abs(points @ n + d) < params.inlier_m]
    n, d = _least_squares_plane(inl)
    for _ in range(params.refine_iterations):
        # the points of an obstacle's foot lie within inlier_m of the floor too; the floor
        # the camera sees in its lower part spans 0.1-0.2 m, so a few hundred of them (1-4 mm up a
        # cylinder COBRA faces) tilted the plane 0.2-0.7 deg, and the floor 0.5-0.9 m away met it
        # 3-6 % off (depth_tolerance 5 %): not ground, and the map took its edge for an obstacle's
        # face (depth world 6 seed 7). Refit to the band of the residuals' own spread.
        res = np.abs(points @ n + d)
        near = res[res < params.inlier_m]
        if len(near) < 3:
            break
        sigma = 1.4826 * float(np.median(near))
        band = min(params.inlier_m, max(params.refine_floor_m, 3.0 * sigma))
        keep = points[res < band]
        if len(keep) < 3:
            break
        inl = keep
        n, d = _least_squares_plane(inl)
    return n, d, len(inl)


def _least_squares_plane(points: np.ndarray) -> Tuple[np.ndarray, float]:
    """(n, d) of the least-squares plane through (N >= 3, 3) points, n towards the origin (d > 0)."""
    centroid = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centroid, full_matrices=False)
    n = vt[2]
    d = -float(n @ centroid)
    if d < 0:
        n, d = -n, -d
    return n, d


class DepthTraversability:
    """Depth image -> binary traversability image, with the plane it used."""

    def __init__(self, intrinsics, T_ground_camera: np.ndarray,
                 params: Optional[DepthTraversabilityParams] = None, seed: int = 0):
        self.k = intrinsics
        self.params = params or DepthTraversabilityParams()
        self.prior_n, self.prior_d = plane_from_mount(T_ground_camera)
        self.rng = np.random.default_rng(seed)
        v, u = np.mgrid[0:self.k.height, 0:self.k.width]
        self._rays = np.dstack([(u - self.k.cx) / self.k.fx, (v - self.k.cy) / self.k.fy,
                                np.ones(u.shape)]).astype(np.float32)
        self.last_plane: Tuple[np.ndarray, float] = (self.prior_n, self.prior_d)
        self.last_plane_fitted = False

    def ground_mask(self, depth_m: np.ndarray) -> np.ndarray:
        """Per pixel: valid depth and within the height threshold of the ground plane."""
        p = self.params
        z = np.asarray(depth_m, float)
        valid = (z > 0) & (z < p.max_range_m)
        s = p.stride_px
        lower = slice(self.k.height // 3, None, s)
        pts = (self._rays[lower, ::s] * z[lower, ::s, None])[valid[lower, ::s]]
        if len(pts) < MIN_LOWER_POINTS:
            # a real sensor has no depth nearer than its minimum range: a head pitched down (or a
            # camera near the floor) sees the floor it can measure only in the image's upper part
            pts = (self._rays[::s, ::s] * z[::s, ::s, None])[valid[::s, ::s]]
        n, d = self.prior_n, self.prior_d
        self.last_plane_fitted = False
        fit = fit_ground_plane(pts, p, self.rng)
        if fit is not None:
            fn, fd, _ = fit
            tilt = np.degrees(np.arccos(np.clip(fn @ self.prior_n, -1.0, 1.0)))
            if tilt <= p.max_plane_tilt_deg and abs(fd - self.prior_d) <= p.max_height_error_m:
                n, d, self.last_plane_fitted = fn, fd, True
        self.last_plane = (n, d)
        # depth at which each ray meets the plane (n.(z ray) + d = 0); rays above the horizon: none
        dot = self._rays @ n.astype(np.float32)
        hits = dot < -1e-6
        expected = np.where(hits, -d / np.where(hits, dot, -1.0), 0.0)
        return valid & hits & (np.abs(z - expected) < p.depth_tolerance * expected)

    def __call__(self, depth_m: np.ndarray) -> np.ndarray:
        """The traversable region (H, W) bool."""
        return self.classify(depth_m).ground

    def classify(self, depth_m: np.ndarray) -> Traversability:
        """The traversable region and the unknown pixels (cells with too little depth, not joined to it)."""
        p = self.params
        z = np.asarray(depth_m, float)
        ground = cell_counts(self.ground_mask(z), p.block_px)
        measured = cell_counts(z > 0, p.block_px)
        unknown = measured < p.min_measured_fraction * p.block_px * p.block_px
        cells = ~unknown & (ground >= p.min_fraction * measured)
        region = grow_from_bottom(fill_unknown_below_ground(cells, unknown))
        return Traversability(expand_cells(region, p.block_px, z.shape),
                              expand_cells(unknown & ~region, p.block_px, z.shape))


def fill_unknown_below_ground(ground: np.ndarray, unknown: np.ndarray) -> np.ndarray:
    """(rows, cols) cells -> ground, plus each unknown cell whose nearest measured cell above it (a
    smaller row) in its column is ground. Unknown cells under an obstacle, or with nothing measured
    above, stay out."""
    ground, unknown = np.asarray(ground, bool), np.asarray(unknown, bool)
    out = ground.copy()
    ground_above = np.zeros(ground.shape[1], bool)
    for r in range(ground.shape[0]):
        out[r] |= unknown[r] & ground_above
        ground_above = np.where(unknown[r], ground_above, ground[r])
    return out
