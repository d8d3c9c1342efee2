"""Issue 13 round 14: the block labels' ground fraction (classifier.ground_fraction,
block_classifier.py): a block is labelled ground, for training and for perception truth, only when
at least this fraction of it is ground; 1.0 calls every block that shows any obstacle not ground."""
import numpy as np
import pytest

from snake_autonomy.perception.block_classifier import BlockClassifier, block_labels, truth_traversable
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from test_nav_block_classifier import synthetic


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


def test_the_config_key(tmp_path):
    from snake_autonomy.paths import config_path
    f = tmp_path / "nav.yaml"
    f.write_text(f"base: {config_path('nav.yaml')}\nclassifier:\n  ground_fraction: 0.0\n")
    with pytest.raises(NavConfigError, match=r"ground_fraction: must be in \(0, 1\], got 0.0"):
        NavConfig.from_yaml(f)
    f.write_text(f"base: {config_path('nav.yaml')}\nclassifier:\n  ground_fraction: 1.0\n")
    assert NavConfig.from_yaml(f).classifier.ground_fraction == 1.0
    assert NavConfig.from_yaml().classifier.ground_fraction == 0.5        # committed: half the block

