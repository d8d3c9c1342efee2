"""The monocular block classifier (perception/block_classifier.py): DCT features, SVM, grown region;
cells at a finer stride than the blocks (each cell judged by the block centred on it), the SVM's
ground margin, and the fraction of a block that must be ground for its label.

On drawn images here (a few seconds); on rendered scenes, precision/recall are the figures of
`snake_autonomy nav train-classifier` (60 training scenes take minutes: not a CI test; README).
"""
import numpy as np
import pytest
from scipy.fft import dctn

from snake_autonomy.perception.block_classifier import (BlockClassifier, block_features, block_labels,
                                                        truth_traversable)
from snake_autonomy.perception.ground_region import cell_grid, precision_recall, traversable, window_origins


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


def test_each_cell_is_judged_by_the_block_centred_on_it():
    assert list(window_origins(120, 40, 40)) == [0, 40, 80]                 # the paper's tiles
    assert list(window_origins(120, 40, 20)) == [0, 10, 30, 50, 70, 80]     # centred, kept inside
    with pytest.raises(ValueError, match="stride_px"):
        window_origins(480, 40, 50)


def test_features_at_a_stride_are_the_dct_of_that_block():
    import cv2
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (480, 640, 3), dtype=np.uint8)
    ycc = cv2.cvtColor(img, cv2.COLOR_RGB2YCrCb).astype(np.float32) / 255.0
    f = block_features(img, 40, 4, 20)
    assert f.shape == (24, 32, 48)
    for r, c in ((0, 0), (5, 7), (23, 31), (12, 0)):
        y, x = window_origins(480, 40, 20)[r], window_origins(640, 40, 20)[c]
        ref = dctn(ycc[y:y + 40, x:x + 40].transpose(2, 0, 1), type=2, axes=(1, 2), norm="ortho")[:, :4, :4]
        assert np.allclose(f[r, c], ref.ravel(), atol=1e-4), (r, c)
    assert np.array_equal(block_features(img, 40, 4, 40), block_features(img, 40, 4))


def _edge_error(edge_px, stride):
    """An obstacle filling the columns left of edge_px: the region's left edge minus edge_px."""
    mask = np.ones((480, 640), bool)
    mask[:, :edge_px] = False
    free_cols = np.flatnonzero(traversable(mask, 40, 0.5, stride).any(axis=0))
    return int(free_cols[0]) - edge_px


def test_a_finer_stride_places_the_obstacle_edge_within_half_a_cell():
    tiles = [_edge_error(e, 40) for e in range(100, 180)]
    cells = [_edge_error(e, 20) for e in range(100, 180)]
    assert max(abs(e) for e in tiles) == 20              # tiles: up to half a tile either way
    assert max(abs(e) for e in cells) <= 10              # 20 px cells: half a cell
    # a 25 px sliver of obstacle across two tiles: half of one, invisible to them; the cell centred
    # on it is judged by a block it fills 25 / 40 of
    mask = np.ones((480, 640), bool)
    mask[:, 100:125] = False
    assert cell_grid(mask, 40).all(axis=0)[2]
    assert not cell_grid(mask, 40, 0.5, 20).all(axis=0).all()


def test_the_model_keeps_its_stride_and_old_models_load_as_tiles(tmp_path):
    import joblib
    rng = np.random.default_rng(0)
    floor = lambda shape: np.clip(rng.normal([150, 120, 100], 25, shape), 0, 255).astype(np.uint8)
    samples = []
    for _ in range(3):
        img = np.empty((480, 640, 3), np.uint8)
        ground = np.zeros((480, 640), bool)
        ground[rng.integers(100, 400):] = True
        img[:] = np.where(ground[..., None], floor((480, 640, 3)), rng.integers(0, 256, 3)).astype(np.uint8)
        samples.append((img, ground))
    clf = BlockClassifier.train(samples, 40, 4, stride_px=20)
    assert clf.classify(samples[0][0]).shape == (24, 32)
    assert clf.traversable(samples[0][0]).shape == (480, 640)
    clf.save(tmp_path / "m.joblib")
    loaded = BlockClassifier.load(tmp_path / "m.joblib")
    assert loaded.stride_px == 20 and loaded.cell_px == 20
    old = joblib.load(tmp_path / "m.joblib")
    del old["stride_px"]                                 # a model written before strides
    joblib.dump(old, tmp_path / "old.joblib")
    assert BlockClassifier.load(tmp_path / "old.joblib").cell_px == 40


def test_held_out_figures_judge_the_classifier_against_truth_through_its_own_cells():
    """`nav train-classifier` / `eval-perception` (cli.evaluate): the truth goes through the
    classifier's block and stride, depth's through its 8 px cells. A few seconds (4 rendered scenes)."""
    import types
    from snake_autonomy.runs.render_set import render_scenes
    from snake_autonomy.cli.nav import _setup, evaluate
    cfg, robot, params = _setup(types.SimpleNamespace(config=None, robot="cobra"))
    frames = list(render_scenes(robot, params, 4, 7, cfg.intrinsics, cfg.mount))
    clf = BlockClassifier.train([(f.rgb, f.ground_truth_ground()) for f in frames[:3]], 40, 4, stride_px=20)
    out = evaluate(cfg, robot, frames[3:], clf)
    assert (out["mono"]["truth_block_px"], out["mono"]["truth_stride_px"]) == (40, 20)
    assert (out["depth"]["truth_block_px"], out["depth"]["truth_stride_px"]) == (8, 8)
    assert out["mono"]["precision"] > 0.8 and out["mono"]["recall"] > 0.8, out["mono"]


@pytest.fixture(scope="module")
def trained():
    rng = np.random.default_rng(0)
    clf = BlockClassifier.train([synthetic(rng, rng.integers(2, 12, 16) * 40) for _ in range(6)], 40, 4)
    img, ground = synthetic(rng, [200] * 8 + [400] * 8)
    return clf, img, ground


def test_margin_zero_is_the_svm_own_class(trained):
    clf, img, _ = trained
    assert np.array_equal(clf.classify(img, 0.0), clf.classify(img))
    # any other margin: exactly the blocks whose decision value exceeds it (positive: ground)
    d = clf.model.decision_function(block_features(img, 40, 4).reshape(-1, 48)).reshape(12, 16)
    assert np.array_equal(clf.classify(img, 0.3), d > 0.3)
    assert np.array_equal(clf.classify(img, -0.3), d > -0.3)


def test_a_larger_margin_calls_fewer_blocks_ground(trained):
    clf, img, _ = trained
    counts = [int(clf.classify(img, m).sum()) for m in (-100.0, -1.0, 0.0, 0.5, 1.0, 100.0)]
    assert counts == sorted(counts, reverse=True)
    assert counts[0] == 12 * 16 and counts[-1] == 0
    # the traversability image follows: grown from the bottom, nothing with an infinite margin
    assert not clf.traversable(img, 100.0).any()
    assert clf.traversable(img, -100.0).all()


def test_the_fraction_moves_an_obstacle_edge_by_up_to_half_a_block():
    # an obstacle right of column 330 (not a cell boundary): 20 px cells, judged by 40 px blocks
    ground = np.ones((480, 640), bool)
    ground[:, 330:] = False
    half = block_labels(ground, 40, 20)                 # 0.5: cell 15 (300-320, block 290-330) ground,
    full = block_labels(ground, 40, 20, 1.0)            # cell 16 (block 310-350: 20 of 40 px) too
    assert half[0, :17].all() and not half[0, 17:].any()
    assert full[0, :16].all() and not full[0, 16:].any()   # 1.0: the block 310-350 shows the obstacle
    # one obstacle pixel in a block is enough with 1.0, never with 0.5
    ground = np.ones((480, 640), bool)
    ground[100, 100] = False
    assert block_labels(ground, 40, 20).all()
    assert not block_labels(ground, 40, 20, 1.0).all()
    # the grown region of perception truth: the same cells, grown from the bottom
    t_half, t_full = truth_traversable(ground, 40, 20), truth_traversable(ground, 40, 20, 1.0)
    assert t_half.all() and not t_full[:100, 100].any() and t_full[120:, :].all()


def test_the_model_keeps_its_training_fraction(tmp_path):
    rng = np.random.default_rng(0)
    samples = [synthetic(rng, rng.integers(2, 12, 16) * 40) for _ in range(4)]
    clf = BlockClassifier.train(samples, 40, 4, stride_px=20, ground_fraction=0.9)
    clf.save(tmp_path / "m.joblib")
    assert BlockClassifier.load(tmp_path / "m.joblib").ground_fraction == 0.9
    half = BlockClassifier.train(samples, 40, 4, stride_px=20)
    assert half.ground_fraction == 0.5
    # trained on its labels: the cells whose block straddles the floor's edge (half floor: ground at
    # 0.5, not at 0.9) are floor for the 0.5 model and not for the 0.9 one
    img, _ = synthetic(rng, [200] * 8 + [400] * 8)
    strict, loose = clf.classify(img), half.classify(img)
    assert not (strict & ~loose).any() and (loose & ~strict).sum() >= 16, (loose & ~strict).sum()
