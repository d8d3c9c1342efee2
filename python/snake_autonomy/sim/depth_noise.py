"""A D435i-like depth sensor model applied to the head camera's perfect depth renders.

    model = DepthNoise(config.depth_noise, intrinsics.fx, params.rng("depth_noise"))
    noisy = model(depth_m)          # (H, W) float32, z along the optical axis, 0 = no depth

What it does to a render (config/sim.yaml depth_noise:, DepthNoiseConfig):
- noise: a zero-mean Gaussian per pixel whose std grows with z^2, the active-stereo RMS error
  formula of Intel's depth tuning guide (sigma_z = z^2 x subpixel / (focal_px x baseline_m)): with
  the D435i's 50 mm baseline, a 0.08 subpixel and the nav camera's 615 px focal, 2.6 mm at 1 m and
  10 mm at 2 m;
- invalid pixels (depth 0) nearer than min_range_m (stereo cannot match below its minimum Z), beyond
  max_range_m, and in a band of edge_band_px pixels around depth discontinuities (a neighbour's
  depth differs by more than edge_jump_fraction of the nearer one: stereo matching fails on the
  occlusion boundary and on grazing surfaces, whose neighbouring pixels also differ steeply).
Every random number comes from the generator given (the run's seed's stream).

sim_node picks the model by name (~depth_model, sim.launch depth_model:=): named_depth_model.
"""
from dataclasses import dataclass
from typing import List, Optional

import numpy as np


@dataclass
class DepthNoiseConfig:
    enabled: bool = True               # nav runs apply it unless --depth-model perfect
    baseline_m: float = 0.05           # D435i stereo baseline (50 mm)
    subpixel: float = 0.08             # disparity RMS in pixels (Intel: 0.05-0.1 on textured scenes)
    # Intel's D400 datasheet (337029, "Minimum-Z depth"): the D435's min-Z is about 105 mm at a
    # 424x240 depth stream and grows with the resolution (about 195 mm at 848x480, 280 mm at
    # 1280x720); 0.105 m takes the low-resolution stream a snake's onboard computer would run.
    min_range_m: float = 0.105
    max_range_m: float = 4.0           # beyond: no depth (at 4 m sigma_z is already 4 cm)
    edge_jump_fraction: float = 0.1    # neighbouring depths differing by more than this x the nearer: an edge
    edge_band_px: int = 2              # pixels each side of an edge without depth

    def problems(self, prefix: str = "depth_noise") -> List[str]:
        """Every invalid value, each naming its key."""
        out = []
        for key in ("baseline_m", "subpixel", "min_range_m", "max_range_m", "edge_jump_fraction"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v <= 0:
                out.append(f"{prefix}.{key}: must be a finite number > 0, got {v!r}")
        if not out and self.min_range_m >= self.max_range_m:
            out.append(f"{prefix}.min_range_m: must be below max_range_m ({self.max_range_m}), got {self.min_range_m}")
        if isinstance(self.edge_band_px, bool) or not isinstance(self.edge_band_px, int) or self.edge_band_px < 0:
            out.append(f"{prefix}.edge_band_px: must be an integer >= 0, got {self.edge_band_px!r}")
        if not isinstance(self.enabled, bool):
            out.append(f"{prefix}.enabled: must be true or false, got {self.enabled!r}")
        return out


def depth_sigma_m(z_m, focal_px: float, baseline_m: float, subpixel: float):
    """The RMS depth error (m) at depth z_m: z^2 x subpixel / (focal_px x baseline_m)."""
    z = np.asarray(z_m, float)
    return z * z * subpixel / (focal_px * baseline_m)


def edge_mask(depth_m: np.ndarray, jump_fraction: float, band_px: int) -> np.ndarray:
    """(H, W) bool: pixels within band_px of a depth discontinuity (4-neighbours differing by more
    than jump_fraction of the nearer depth; a valid pixel beside a pixel without depth is one too)."""
    z = np.asarray(depth_m, float)
    edge = np.zeros(z.shape, bool)
    for a, b, ia, ib in ((z[:, 1:], z[:, :-1], np.s_[:, 1:], np.s_[:, :-1]),
                         (z[1:, :], z[:-1, :], np.s_[1:, :], np.s_[:-1, :])):
        near = np.minimum(a, b)
        jump = (np.abs(a - b) > jump_fraction * near) & (np.maximum(a, b) > 0)
        edge[ia] |= jump
        edge[ib] |= jump
    if band_px > 1:
        edge = _dilate(edge, band_px - 1)
    return edge


def _dilate(mask: np.ndarray, r: int) -> np.ndarray:
    """Square dilation by r pixels (shifts: no SciPy needed in the render path)."""
    out = mask.copy()
    for axis in (0, 1):
        grown = out.copy()
        for s in range(1, r + 1):
            fwd = np.roll(out, s, axis=axis)
            bwd = np.roll(out, -s, axis=axis)
            if axis == 0:
                fwd[:s, :], bwd[-s:, :] = False, False
            else:
                fwd[:, :s], bwd[:, -s:] = False, False
            grown |= fwd | bwd
        out = grown
    return out


class DepthNoise:
    """Perfect depth -> D435i-like depth (see the module's docstring)."""

    def __init__(self, config: DepthNoiseConfig, focal_px: float, rng: np.random.Generator):
        problems = config.problems()
        if not (isinstance(focal_px, (int, float)) and np.isfinite(focal_px) and focal_px > 0):
            problems.append(f"focal_px: must be a finite number > 0, got {focal_px!r}")
        if problems:
            raise ValueError("depth noise: " + "; ".join(problems))
        self.config, self.focal_px, self.rng = config, float(focal_px), rng

    def sigma_m(self, z_m):
        c = self.config
        return depth_sigma_m(z_m, self.focal_px, c.baseline_m, c.subpixel)

    def __call__(self, depth_m: np.ndarray) -> np.ndarray:
        c = self.config
        z = np.asarray(depth_m, np.float32)
        noise = self.rng.standard_normal(z.shape).astype(np.float32)   # drawn for every pixel: a fixed stream
        out = z + noise * self.sigma_m(z).astype(np.float32)
        invalid = (z <= 0) | (z < c.min_range_m) | (z > c.max_range_m)
        if c.edge_band_px > 0:
            invalid |= edge_mask(z, c.edge_jump_fraction, c.edge_band_px)
        out[invalid] = 0.0
        return out


#: sim_node's ~depth_model: the D435i-like model of config/sim.yaml depth_noise:, or exact renders
NAMED_DEPTH_MODELS = ("d435i", "perfect")


def named_depth_model(name: str, config: DepthNoiseConfig, focal_px: float,
                      rng: np.random.Generator) -> Optional[DepthNoise]:
    """The depth model called `name` (NAMED_DEPTH_MODELS): a DepthNoise for "d435i", None (exact
    depth) for "perfect". config.enabled is the batch nav runs' default and is not read: the name
    decides. ValueError naming depth_model for any other name."""
    if name not in NAMED_DEPTH_MODELS:
        raise ValueError(f"depth_model: expected one of {', '.join(NAMED_DEPTH_MODELS)}, got {name!r}")
    return DepthNoise(config, focal_px, rng) if name == "d435i" else None
