"""The planner's batched FK and cost against the core's one-posture FK: the same frames, the same
cost, a gradient that matches finite differences of the reference cost."""
import numpy as np
import pytest

from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.cost import Directive, StageCost, Weights
from snake_autonomy.sim.config import servo_torque_limit_nm


@pytest.fixture(scope="module", params=["unified_snake", "cobra"])
def planner(request, root):
    return build_planner(str(root / f"config/robots/{request.param}.yaml"), torque_limit_nm=servo_torque_limit_nm())[0]


@pytest.mark.parametrize("m", [2, 5])
def test_batched_frames_match_the_core_fk(planner, m):
    chain = planner.chain
    rng = np.random.default_rng(m)
    q_start = chain.q_lying + rng.uniform(-0.3, 0.3, chain.num_joints)
    kin = chain.stage_kinematics(q_start, m)
    q_active = q_start[:m] + rng.uniform(-1.0, 1.0, (7, m))
    pos, com = kin.positions_com(q_active)
    for k in range(len(q_active)):
        q = q_start.copy()
        q[:m] = q_active[k]
        ref = chain.pose(q)
        np.testing.assert_allclose(pos[k], ref.positions, atol=1e-12)
        np.testing.assert_allclose(com[k], ref.com, atol=1e-12)


def test_batched_cost_and_gradient_match_the_reference(planner):
    chain, m = planner.chain, 4
    cost = StageCost(chain, chain.q_lying, m, planner.support(m), Weights(k_torque=0.0),
                     Directive(), 3.0, 9)
    rng = np.random.default_rng(0)
    delta = rng.uniform(-0.4, 0.4, m)
    # the reference: per-sample core FK, as the planner computed Cs before batching
    poses = cost.poses(delta, cost.t_s)
    zmp = np.array([p.zmp for p in poses])
    from snake_autonomy.planning.fbsr.cost import stability_cost
    cs = stability_cost(cost.support.signed_distance(zmp), cost.w.ks_per_m2, cost.w.k_out_per_m2)
    assert cost.terms(delta)["Cs"] == pytest.approx(float(cost._trapezoid @ cs), rel=1e-12)
    assert cost.terms(delta)["Cd"] == pytest.approx(-poses[-1].head[2], rel=1e-12)
    value, grad = cost.value_and_gradient(delta, 1e-6, np.full(m, 9.0), np.full(m, 9.0))
    assert value == pytest.approx(cost(delta), rel=1e-12)
    central = [(cost(delta + e) - cost(delta - e)) / 2e-6 for e in np.eye(m) * 1e-6]
    np.testing.assert_allclose(grad, central, rtol=1e-3, atol=1e-4)
