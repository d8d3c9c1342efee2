"""The monocular block classifier (perception/block_classifier.py): DCT features, SVM, grown region.

On drawn images here (a few seconds); on rendered scenes, precision/recall are the figures of
`snake_autonomy nav train-classifier` (60 training scenes take minutes: not a CI test; README).
"""
import numpy as np
import pytest

from snake_autonomy.perception.block_classifier import BlockClassifier, block_features, block_labels
from snake_autonomy.perception.ground_region import precision_recall, traversable


def synthetic(rng, boundary_rows):
    """Carpet-like noisy floor below boundary_rows[col block], smooth coloured obstacles above."""
    img = np.empty((480, 640, 3), np.uint8)
    floor = np.clip(rng.normal([150, 120, 100], 25, (480, 640, 3)), 0, 255)
    obstacle = np.clip(rng.normal(rng.uniform(20, 235, 3), 3, (480, 640, 3)), 0, 255)
    ground = np.zeros((480, 640), bool)
    for c, row in enumerate(boundary_rows):
        ground[row:, c * 40:(c + 1) * 40] = True
    img[:] = np.where(ground[..., None], floor, obstacle).astype(np.uint8)
    return img, ground


def test_features_shape_and_dc_term():
    img = np.full((480, 640, 3), 200, np.uint8)
    f = block_features(img, 40, 4)
    assert f.shape == (12, 16, 48)
    # a flat block: only the DC coefficient of each channel is non-zero; DC = 40 * mean (orthonormal)
    assert np.allclose(f[..., 1:16], 0, atol=1e-4)
    assert f[0, 0, 0] == pytest.approx(40 * 200 / 255.0, rel=1e-3)
    labels = block_labels(np.vstack([np.zeros((240, 640), bool), np.ones((240, 640), bool)]), 40)
    assert labels[:6].sum() == 0 and labels[6:].all()


def test_classifier_learns_texture_and_grows_from_the_bottom(tmp_path):
    rng = np.random.default_rng(0)
    train = [synthetic(rng, rng.integers(2, 12, 16) * 40) for _ in range(6)]
    clf = BlockClassifier.train(train, 40, 4)
    img, ground = synthetic(rng, [200] * 8 + [400] * 8)
    # a floor-like patch above the obstacle in column block 0: not reachable, must not count
    img[40:120, 0:40] = np.clip(rng.normal([150, 120, 100], 25, (80, 40, 3)), 0, 255).astype(np.uint8)
    pred = clf.traversable(img)
    prec, rec = precision_recall(pred, traversable(ground, 40))
    assert prec > 0.97 and rec > 0.97
    assert not pred[40:120, 0:40].any()
    path = tmp_path / "results" / "nav" / "m.joblib"      # a folder that does not exist yet
    clf.save(path)
    assert np.array_equal(BlockClassifier.load(path).traversable(img), pred)
    (tmp_path / "bad.joblib").write_bytes(b"")
    import joblib
    joblib.dump({"format": "other"}, tmp_path / "bad.joblib")
    with pytest.raises(ValueError, match="not a block classifier model"):
        BlockClassifier.load(tmp_path / "bad.joblib")
