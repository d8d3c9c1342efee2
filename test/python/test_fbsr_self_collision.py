"""Self-collision of the modules as capsules (planning/fbsr/collision.py): the segment distance on
known cases."""
import numpy as np
import pytest

from snake_autonomy.planning.fbsr import collision

SEGMENTS = [
    # (p1, q1, p2, q2, distance): what the case is
    ((0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), 1.0),                  # parallel, side by side
    ((0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0), 1.0),                  # collinear, end to end
    ((0, 0, 0), (1, 0, 0), (0.5, 0, 0), (3, 0, 0), 0.0),                # collinear, overlapping
    ((0, 0, 0), (1, 0, 0), (3, 1, 0), (4, 1, 0), np.hypot(2, 1)),       # parallel, offset: end points
    ((-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), 0.0),                # crossing
    ((-1, 0, 0), (1, 0, 0), (0, -1, 0.3), (0, 1, 0.3), 0.3),            # skew, closest inside both
    ((0, 0, 0), (1, 0, 0), (2, -1, 0.5), (2, 1, 0.5), np.hypot(1, 0.5)),  # skew, end of one
    ((0, 0, 0), (1, 0, 0), (1, 1, 0), (2, 2, 0), 1.0),                  # V: end to end
    ((0, 0, 0), (0, 0, 0), (0, -1, 2), (0, 1, 2), 2.0),                 # a point and a segment
    ((1, 1, 1), (1, 1, 1), (1, 1, 4), (1, 1, 4), 3.0),                  # two points
]


@pytest.mark.parametrize("p1, q1, p2, q2, expected", SEGMENTS)
def test_segment_distance_matches_known_cases(p1, q1, p2, q2, expected):
    assert collision.segment_distances(p1, q1, p2, q2) == pytest.approx(expected, abs=1e-12)
    # symmetric, and independent of each segment's direction
    assert collision.segment_distances(q2, p2, q1, p1) == pytest.approx(expected, abs=1e-12)


def test_segment_distance_matches_dense_sampling_on_random_segments():
    rng = np.random.default_rng(7)
    a, b, c, d = rng.normal(size=(4, 200, 3))
    got = collision.segment_distances(a, b, c, d)
    u = np.linspace(0, 1, 201)
    for k in range(len(a)):
        x = a[k] + (b[k] - a[k]) * u[:, None]
        y = c[k] + (d[k] - c[k]) * u[:, None]
        brute = np.linalg.norm(x[:, None] - y[None], axis=2).min()
        assert got[k] <= brute + 1e-12
        assert got[k] == pytest.approx(brute, abs=2e-2 * np.linalg.norm(b[k] - a[k] + d[k] - c[k]) + 1e-3)


def test_pairs_leave_out_neighbours_and_still_modules():
    assert collision.module_pairs(4).tolist() == [[0, 2], [0, 3], [1, 3]]
    assert collision.module_pairs(5, moving_below=1).tolist() == [[0, 2], [0, 3], [0, 4]]


def test_clearance_of_a_folded_chain_is_negative_where_capsules_overlap():
    # three unit modules folded into a U whose arms are 0.1 apart: modules 0 and 2 overlap by
    # 2 x 0.06 - 0.1 = 0.02 m
    frames = np.array([[1.0, 0.0, 0], [0.0, 0.0, 0], [0.0, 0.1, 0], [1.0, 0.1, 0]])
    c, pair = collision.worst_clearance(frames, 0.06)
    assert pair == (0, 2)
    assert c == pytest.approx(-0.02)
