"""Monocular traversability (Chang et al. III, after Hadjidemetriou et al.): 40x40 pixel blocks,
DCT features, a support vector machine: ground / not ground; the region grown from the bottom.

Features of a block: per colour channel (YCrCb), the k x k lowest-frequency coefficients of the
block's 2-D DCT-II (orthonormal), the DC term and the low frequencies carrying colour, brightness
and texture; 3 k^2 values (108 for k = 6). The SVM (RBF kernel, scikit-learn) sits behind a
standard scaler. A block is labelled ground for training when at least half its pixels are ground
in the segmentation render (nav.yaml classifier.ground_fraction, kept in the model file).

Stride (ground_region.py): each cell of stride_px pixels is judged by the block centred on
it; stride_px = block_px is the paper's tiling. Training uses the blocks of the same grid.

The model is a file written by `snake_autonomy nav train-classifier --out FILE` (joblib), never a
committed blob: the command renders its own training set.
"""
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Optional, Tuple

import cv2
import numpy as np
from scipy.fft import dct

from .ground_region import cell_grid, expand_cells, grow_from_bottom, traversable, window_origins

MODEL_FORMAT = "snake_autonomy.block_classifier/1"
GROUND_FRACTION = 0.5               # a block is labelled ground when at least this much of it is


def block_features(rgb: np.ndarray, block_px: int = 40, k: int = 6, stride_px: Optional[int] = None) -> np.ndarray:
    """(H, W, 3) uint8 RGB -> (rows, cols, 3 k^2) float32: the k x k lowest coefficients of the
    orthonormal 2-D DCT-II of the block judging each cell (window_origins; stride_px default
    block_px: whole tiles), per channel."""
    ycc = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2YCrCb).astype(np.float32) / 255.0
    h, w = ycc.shape[:2]
    s = stride_px or block_px
    ys, xs = window_origins(h, block_px, s), window_origins(w, block_px, s)
    # the first k rows of the orthonormal DCT-II matrix: C B C^T is dctn(B, norm="ortho")[:k, :k]
    c = dct(np.eye(block_px, dtype=np.float64), type=2, axis=0, norm="ortho")[:k].astype(np.float32)
    span = np.arange(block_px)
    cols = ycc[:, xs[:, None] + span]                            # H, cols, bx, ch
    along_x = np.einsum("jx,hcxn->hcnj", c, cols)                # separable: x first, then y
    rows = along_x[ys[:, None] + span]                           # rows, by, cols, ch, j
    coeffs = np.einsum("iy,rycnj->rcnij", c, rows)
    return np.ascontiguousarray(coeffs.reshape(len(ys), len(xs), -1), dtype=np.float32)


def block_labels(ground: np.ndarray, block_px: int = 40, stride_px: Optional[int] = None,
                 ground_fraction: float = GROUND_FRACTION) -> np.ndarray:
    """(H, W) bool ground truth -> (rows, cols) bool: at least ground_fraction of the block judging
    the cell is ground (0.5: half; 1.0: a block that shows any obstacle is not ground)."""
    return cell_grid(ground, block_px, ground_fraction, stride_px)


def truth_traversable(ground: np.ndarray, block_px: int = 40, stride_px: Optional[int] = None,
                      ground_fraction: float = GROUND_FRACTION) -> np.ndarray:
    """(H, W) bool ground truth -> the traversability image a perfect classifier would give: the
    training labels (block_labels) grown from the bottom, at pixel resolution."""
    return traversable(ground, block_px, ground_fraction, stride_px)


@dataclass
class BlockClassifier:
    model: object                   # sklearn Pipeline(scaler, SVC)
    block_px: int = 40
    k: int = 6
    stride_px: Optional[int] = None   # cells judged by the block centred on each; None: block_px
    ground_fraction: float = GROUND_FRACTION   # the training labels' threshold (block_labels)

    @property
    def cell_px(self) -> int:
        """The traversability image's cell: stride_px, or the tile."""
        return self.stride_px or self.block_px

    @classmethod
    def train(cls, samples: Iterable[Tuple[np.ndarray, np.ndarray]], block_px: int = 40, k: int = 6,
              c: float = 10.0, gamma="scale", stride_px: Optional[int] = None,
              ground_fraction: float = GROUND_FRACTION) -> "BlockClassifier":
        """samples: (rgb, ground mask) pairs; the blocks of every cell of stride_px, labelled ground
        when at least ground_fraction of the block is."""
        from sklearn.pipeline import make_pipeline  # lazy: scikit-learn is heavy and only this path needs it
        from sklearn.preprocessing import StandardScaler
        from sklearn.svm import SVC
        xs, ys = [], []
        for rgb, ground in samples:
            xs.append(block_features(rgb, block_px, k, stride_px).reshape(-1, 3 * k * k))
            ys.append(block_labels(ground, block_px, stride_px, ground_fraction).ravel())
        x, y = np.vstack(xs), np.concatenate(ys)
        model = make_pipeline(StandardScaler(), SVC(C=c, gamma=gamma, class_weight="balanced"))
        model.fit(x, y)
        return cls(model, block_px, k, stride_px, ground_fraction)

    def classify(self, rgb: np.ndarray, ground_margin: float = 0.0) -> np.ndarray:
        """(rows, cols) bool per cell: its block looks like ground (ground_margin != 0: its SVM
        decision value exceeds ground_margin; > 0 calls fewer blocks ground)."""
        f = block_features(rgb, self.block_px, self.k, self.stride_px)
        x = f.reshape(-1, f.shape[-1])
        if ground_margin == 0.0:
            return self.model.predict(x).reshape(f.shape[:2]).astype(bool)
        sign = 1.0 if bool(self.model.classes_[1]) else -1.0       # decision > 0: classes_[1]
        return (sign * self.model.decision_function(x) > ground_margin).reshape(f.shape[:2])

    def traversable(self, rgb: np.ndarray, ground_margin: float = 0.0) -> np.ndarray:
        """The binary traversability image: blocks grown from the bottom, at pixel resolution."""
        return expand_cells(grow_from_bottom(self.classify(rgb, ground_margin)), self.cell_px, rgb.shape[:2])

    def save(self, path) -> None:
        """Writes the model; creates the parent folder (`--out results/nav/block_svm.joblib` on a fresh
        checkout, where results/nav does not exist yet)."""
        import joblib  # lazy: joblib is heavy and only this path needs it
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        joblib.dump({"format": MODEL_FORMAT, "block_px": self.block_px, "k": self.k,
                     "stride_px": self.stride_px, "ground_fraction": self.ground_fraction,
                     "model": self.model}, path)

    @classmethod
    def load(cls, path) -> "BlockClassifier":
        import joblib  # lazy: joblib is heavy and only this path needs it
        d = joblib.load(path)
        if not isinstance(d, dict) or d.get("format") != MODEL_FORMAT:
            raise ValueError(f"{path}: not a block classifier model (format "
                             f"{d.get('format') if isinstance(d, dict) else type(d).__name__!r}, "
                             f"expected {MODEL_FORMAT!r}); make one with `snake_autonomy nav "
                             f"train-classifier --out FILE`")
        stride = d.get("stride_px")                   # absent in older model files: tiles
        return cls(d["model"], int(d["block_px"]), int(d["k"]), None if stride is None else int(stride),
                   float(d.get("ground_fraction", GROUND_FRACTION)))   # absent in older model files: 0.5
