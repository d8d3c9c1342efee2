"""Self-collision of the modules as capsules (planning/fbsr/collision.py): the segment distance on
known cases, and the planner's output checked with it independently of the planner's own terms."""
import dataclasses
import types

import numpy as np
import pytest

from snake_autonomy.planning.fbsr import collision
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.plan_io import stage_samples
from snake_autonomy.planning.fbsr.planner import FbsrPlanner
from snake_autonomy.planning.fbsr.stage import Checks, PlanningError
from snake_autonomy.planning.fbsr.support import Support
from snake_autonomy.sim.config import servo_torque_limit_nm

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


@pytest.fixture(scope="module")
def unified():
    return build_planner("unified_snake", torque_limit_nm=servo_torque_limit_nm())[0]


def _plan_clearance(plan, period_s=0.05):
    r = plan.chain.radius_m
    frames = np.array([plan.chain.positions_com(q)[0] for _, _, q in stage_samples(plan, period_s)])
    return collision.worst_clearance(frames, r)


def test_unified_snake_plan_keeps_its_modules_apart(unified):
    """Seed 3 of the unified snake (12 active modules) once swept modules 6 and 13 8 mm into each
    other: at every sample of every stage, the lying posture included, non-adjacent modules keep
    the configured margin."""
    plan = unified.plan(seed=3)
    clearance, pair = _plan_clearance(plan)
    assert clearance >= unified.cfg.self_collision_margin_m, f"modules {pair}: {clearance * 1e3:.1f} mm"


def test_cobra_plan_keeps_its_modules_apart():
    """COBRA's first raise once swept module 1 about 10 mm into tail module 11 (its curled tail)."""
    planner = build_planner("cobra", torque_limit_nm=servo_torque_limit_nm())[0]
    plan = planner.plan(seed=0)
    clearance, pair = _plan_clearance(plan)
    assert clearance >= planner.cfg.self_collision_margin_m, f"modules {pair}: {clearance * 1e3:.1f} mm"


def test_a_lying_posture_whose_modules_touch_is_refused_with_the_reason(unified):
    """A margin the lying posture cannot keep (its closest non-adjacent modules are 13 mm apart)."""
    planner = FbsrPlanner(unified.robot, dataclasses.replace(unified.cfg, self_collision_margin_m=0.02),
                          unified.posture)
    with pytest.raises(PlanningError, match=r"lying posture: modules \d+ and \d+ come 13\.1 mm apart"):
        planner.plan(max_active=2, seed=0)


def test_stage_check_refuses_a_sample_where_modules_overlap(unified):
    """The stage's global check sees every 50 ms sample: the U-folded chain of three modules at
    one sample (0 and 2 overlap by 20 mm) fails it with the modules and the depth."""
    folded = np.array([[1.0, 0.0, 0.5], [0.0, 0.0, 0.5], [0.0, 0.1, 0.5], [1.0, 0.1, 0.5]])
    ok = folded.copy()
    ok[:, 1] *= 3.0                                    # the arms 0.3 m apart: clear
    samples = np.stack([ok] * 30 + [folded] + [ok] * 30)

    class Folded:                                      # what Checks reads of a StageCost
        t_end_s, m, pipe = 3.0, 3, None
        chain = types.SimpleNamespace(radius_m=0.06)

        def positions_com(self, _delta, t_s):
            assert len(t_s) == len(samples)
            return samples, np.zeros((len(samples), 3))

    everywhere = Support.of([[-5, -5], [5, -5], [5, 5], [-5, 5]])
    problems = Checks(everywhere, self_margin_m=0.002).failures(Folded(), None)
    assert problems == ["modules 0 and 2 overlap by 20.0 mm (self-collision: capsules at least 2.0 mm apart)"]
    samples[30] = ok
    assert Checks(everywhere, self_margin_m=0.002).failures(Folded(), None) == []
