"""The traversable region of a ground mask, grown from the bottom of the image (Chang et al. III).

The camera is assumed to see ground from the bottom centre of the image up towards the horizon,
meeting obstacles first: per column of cells (blocks of block_px x block_px pixels), the ground
region runs from the bottom row up to the first cell that is not ground. Everything above is not
traversable, whatever it looks like (floor seen beyond an obstacle is not reachable straight on).

Cells and windows: a block of block_px x block_px pixels is judged as a whole (the
classifier's DCT features, or its ground fraction); the image is divided into cells of stride_px,
each judged by the block centred on it (shifted inside the image at the borders). stride_px =
block_px is the paper's tiling; a smaller stride keeps the block's features but places the region's
edges stride_px apart. With 40 px tiles COBRA's mono runs failed where the segmentation render
itself, put through the same tiles, fails (2 of 10 runs; 9 of 10 at a 20 px stride).
"""
from typing import NamedTuple

import numpy as np


class Traversability(NamedTuple):
    """A traversability image with what it could not judge: ground (H, W) bool, the traversable region;
    unknown (H, W) bool, the pixels with no measurement (a depth camera's invalid pixels: beyond its
    range, the floor at grazing angles, occlusion edges). Where a column's ground region ends at an
    unknown pixel, the region's edge is where the sensor stopped seeing, not an obstacle's face."""
    ground: np.ndarray
    unknown: np.ndarray


def window_origins(n_px: int, block_px: int, stride_px: int) -> np.ndarray:
    """Along one image axis of n_px pixels: the first pixel of the block judging each cell of
    stride_px (n_px // stride_px cells), the block centred on its cell, inside the image."""
    if not 0 < stride_px <= block_px <= n_px:
        raise ValueError(f"stride_px: expected 0 < stride_px ({stride_px}) <= block_px ({block_px}) "
                         f"<= the image's {n_px} px")
    n = n_px // stride_px
    return np.clip(np.arange(n) * stride_px + (stride_px - block_px) // 2, 0, n_px - block_px)


def cell_counts(mask: np.ndarray, block_px: int, stride_px=None) -> np.ndarray:
    """(H, W) bool -> (H // s, W // s) int (s: stride_px, default block_px): how many pixels of the
    block judging each cell (window_origins) are set. Rows/columns beyond whole cells are dropped
    (the caller's image sizes are multiples of s)."""
    s = stride_px or block_px
    h, w = mask.shape
    ys, xs = window_origins(h, block_px, s), window_origins(w, block_px, s)
    ii = np.zeros((h + 1, w + 1), np.int64)
    ii[1:, 1:] = np.cumsum(np.cumsum(np.asarray(mask, bool), axis=0, dtype=np.int64), axis=1)
    y, x, b = ys[:, None], xs[None, :], block_px
    return ii[y + b, x + b] - ii[y, x + b] - ii[y + b, x] + ii[y, x]


def cell_grid(mask: np.ndarray, block_px: int, min_fraction: float = 0.5, stride_px=None) -> np.ndarray:
    """(H, W) bool -> (H // s, W // s) bool: a cell is ground when at least min_fraction of the
    block judging it is (cell_counts)."""
    return cell_counts(mask, block_px, stride_px) >= min_fraction * block_px * block_px


def grow_from_bottom(cells: np.ndarray) -> np.ndarray:
    """Per column, the cells from the bottom row up to (not including) the first non-ground cell."""
    c = np.asarray(cells, bool)
    # cumulative product from the bottom: stays 1 while every cell below (and this one) is ground
    return np.flip(np.cumprod(np.flip(c, axis=0), axis=0), axis=0).astype(bool)


def expand_cells(cells: np.ndarray, block_px: int, shape) -> np.ndarray:
    """Cells back to a pixel image of `shape` (pixels beyond whole cells: not ground)."""
    out = np.zeros(shape, bool)
    big = np.repeat(np.repeat(cells, block_px, axis=0), block_px, axis=1)
    out[:big.shape[0], :big.shape[1]] = big
    return out


def traversable(mask: np.ndarray, block_px: int, min_fraction: float = 0.5, stride_px=None) -> np.ndarray:
    """Ground mask (H, W) -> the binary traversability image (H, W) of the region grown from the
    bottom, at cell resolution (cells of stride_px, default block_px: cell_grid)."""
    cells = grow_from_bottom(cell_grid(mask, block_px, min_fraction, stride_px))
    return expand_cells(cells, stride_px or block_px, mask.shape)


def precision_recall(predicted: np.ndarray, truth: np.ndarray):
    """(precision, recall) of predicted ground pixels against true ground pixels."""
    p, t = np.asarray(predicted, bool), np.asarray(truth, bool)
    tp = float(np.count_nonzero(p & t))
    prec = tp / max(1.0, float(np.count_nonzero(p)))
    rec = tp / max(1.0, float(np.count_nonzero(t)))
    return prec, rec
