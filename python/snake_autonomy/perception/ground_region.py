"""The traversable region of a ground mask, grown from the bottom of the image (Chang et al. III).

The camera is assumed to see ground from the bottom centre of the image up towards the horizon,
meeting obstacles first: per column of cells (blocks of block_px x block_px pixels), the ground
region runs from the bottom row up to the first cell that is not ground. Everything above is not
traversable, whatever it looks like (floor seen beyond an obstacle is not reachable straight on).
"""
import numpy as np


def cell_grid(mask: np.ndarray, block_px: int, min_fraction: float = 0.5) -> np.ndarray:
    """(H, W) bool -> (H // b, W // b) bool: a cell is ground when at least min_fraction of it is.
    Rows/columns beyond whole cells are dropped (the caller's image sizes are multiples of b)."""
    h, w = mask.shape
    rows, cols = h // block_px, w // block_px
    m = mask[:rows * block_px, :cols * block_px].reshape(rows, block_px, cols, block_px)
    return m.mean(axis=(1, 3)) >= min_fraction


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


def traversable(mask: np.ndarray, block_px: int, min_fraction: float = 0.5) -> np.ndarray:
    """Ground mask (H, W) -> the binary traversability image (H, W) of the region grown from the
    bottom, at cell resolution."""
    cells = grow_from_bottom(cell_grid(mask, block_px, min_fraction))
    return expand_cells(cells, block_px, mask.shape)


def precision_recall(predicted: np.ndarray, truth: np.ndarray):
    """(precision, recall) of predicted ground pixels against true ground pixels."""
    p, t = np.asarray(predicted, bool), np.asarray(truth, bool)
    tp = float(np.count_nonzero(p & t))
    prec = tp / max(1.0, float(np.count_nonzero(p)))
    rec = tp / max(1.0, float(np.count_nonzero(t)))
    return prec, rec
