"""Issue 13 round 13: the monocular classifier's ground margin (classifier.ground_margin,
block_classifier.py): a block is ground when the SVM's decision value exceeds it."""
import numpy as np
import pytest

from snake_autonomy.perception.block_classifier import BlockClassifier, block_features
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from test_nav_block_classifier import synthetic


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


def test_the_config_key(tmp_path):
    from snake_autonomy.paths import config_path
    assert NavConfig.from_yaml().classifier.ground_margin == 0.0           # the committed: the SVM's class
    f = tmp_path / "nav.yaml"
    f.write_text(f"base: {config_path('nav.yaml')}\nclassifier:\n  ground_margin: .nan\n")
    with pytest.raises(NavConfigError, match="ground_margin: must be finite, got nan"):
        NavConfig.from_yaml(f)
    f.write_text(f"base: {config_path('nav.yaml')}\nclassifier:\n  ground_margin: 0.25\n")
    assert NavConfig.from_yaml(f).classifier.ground_margin == 0.25
