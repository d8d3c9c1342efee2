"""Monocular traversability (Chang et al. III, after Hadjidemetriou et al.): 40x40 pixel blocks,
DCT features, a support vector machine: ground / not ground; the region grown from the bottom.

Features of a block: per colour channel (YCrCb), the k x k lowest-frequency coefficients of the
block's 2-D DCT-II (orthonormal), the DC term and the low frequencies carrying colour, brightness
and texture; 3 k^2 values (108 for k = 6). The SVM (RBF kernel, scikit-learn) sits behind a
standard scaler. A block is labelled ground for training when at least half its pixels are ground
in the segmentation render.

The model is a file written by `snake_autonomy nav train-classifier --out FILE` (joblib), never a
committed blob: the command renders its own training set.
"""
from dataclasses import dataclass
from typing import Iterable, Tuple

import cv2
import numpy as np
from scipy.fft import dctn

from .ground_region import cell_grid, expand_cells, grow_from_bottom

MODEL_FORMAT = "snake_autonomy.block_classifier/1"


def block_features(rgb: np.ndarray, block_px: int = 40, k: int = 6) -> np.ndarray:
    """(H, W, 3) uint8 RGB -> (rows, cols, 3 k^2) float32 DCT features of each whole block."""
    ycc = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2YCrCb).astype(np.float32) / 255.0
    h, w = ycc.shape[:2]
    rows, cols = h // block_px, w // block_px
    blocks = ycc[:rows * block_px, :cols * block_px].reshape(rows, block_px, cols, block_px, 3)
    blocks = blocks.transpose(0, 2, 4, 1, 3)                     # rows, cols, ch, by, bx
    coeffs = dctn(blocks, type=2, axes=(3, 4), norm="ortho")[..., :k, :k]
    return coeffs.reshape(rows, cols, -1).astype(np.float32)


def block_labels(ground: np.ndarray, block_px: int = 40) -> np.ndarray:
    """(H, W) bool ground truth -> (rows, cols) bool: at least half the block is ground."""
    return cell_grid(ground, block_px, 0.5)


@dataclass
class BlockClassifier:
    model: object                   # sklearn Pipeline(scaler, SVC)
    block_px: int = 40
    k: int = 6

    @classmethod
    def train(cls, samples: Iterable[Tuple[np.ndarray, np.ndarray]], block_px: int = 40, k: int = 6,
              c: float = 10.0, gamma="scale") -> "BlockClassifier":
        """samples: (rgb, ground mask) pairs."""
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler
        from sklearn.svm import SVC
        xs, ys = [], []
        for rgb, ground in samples:
            xs.append(block_features(rgb, block_px, k).reshape(-1, 3 * k * k))
            ys.append(block_labels(ground, block_px).ravel())
        x, y = np.vstack(xs), np.concatenate(ys)
        model = make_pipeline(StandardScaler(), SVC(C=c, gamma=gamma, class_weight="balanced"))
        model.fit(x, y)
        return cls(model, block_px, k)

    def classify(self, rgb: np.ndarray) -> np.ndarray:
        """(rows, cols) bool: block looks like ground."""
        f = block_features(rgb, self.block_px, self.k)
        return self.model.predict(f.reshape(-1, f.shape[-1])).reshape(f.shape[:2]).astype(bool)

    def traversable(self, rgb: np.ndarray) -> np.ndarray:
        """The binary traversability image: blocks grown from the bottom, at pixel resolution."""
        return expand_cells(grow_from_bottom(self.classify(rgb)), self.block_px, rgb.shape[:2])

    def save(self, path) -> None:
        import joblib
        joblib.dump({"format": MODEL_FORMAT, "block_px": self.block_px, "k": self.k,
                     "model": self.model}, path)

    @classmethod
    def load(cls, path) -> "BlockClassifier":
        import joblib
        d = joblib.load(path)
        if not isinstance(d, dict) or d.get("format") != MODEL_FORMAT:
            raise ValueError(f"{path}: not a block classifier model (format "
                             f"{d.get('format') if isinstance(d, dict) else type(d).__name__!r}, "
                             f"expected {MODEL_FORMAT!r}); make one with `snake_autonomy nav "
                             f"train-classifier --out FILE`")
        return cls(d["model"], int(d["block_px"]), int(d["k"]))
