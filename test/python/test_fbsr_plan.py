"""A short FBSR plan end to end: the ZMP inside U at every sample, plan.json as the contract says,
the lowering back to the lying posture, and the CLI's errors (one message, exit 1)."""
import json

import numpy as np
import pytest

from snake_autonomy import cli
from snake_autonomy.planning.fbsr import plan_io
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.planner import lowering
from snake_autonomy.sim.config import servo_torque_limit_nm


@pytest.fixture(scope="module")
def planner(root):
    return build_planner(str(root / "config/robots/unified_snake.yaml"), torque_limit_nm=servo_torque_limit_nm())[0]


@pytest.mark.parametrize("seed", [0, 1])
def test_short_plan_keeps_the_zmp_inside_and_raises_the_head(planner, seed):
    plan = planner.plan(max_active=4, seed=seed)
    assert plan.active_modules == 4
    assert plan.final_head_height_m > 0.15          # 4 modules lying: head at 0.025 m
    doc = plan_io.to_dict(plan)
    assert plan_io.problems(doc, planner.robot.num_joints, planner.robot.num_frames) == []
    for s in doc["samples"]:                       # strictly inside by the planner's margin
        d = planner.support(s["active_modules"]).signed_distance([s["zmp_m"]])[0]
        assert d > 0


def test_last_raise_ends_above_every_earlier_raise(planner):
    """Seed 3 of the unified snake once ended at 0.100 m with 12 active modules after an earlier
    raise had the head at 0.348 m: the shifts lower the head and the last raise only had to beat
    the head after the last shift. Now it must beat the highest raise (re-planned otherwise)."""
    plan = planner.plan(seed=3)
    raises = [planner.chain.pose(st.q_end).head[2] for st in plan.stages if st.kind == "raise"]
    assert plan.active_modules == 12
    assert plan.final_head_height_m == pytest.approx(raises[-1])
    assert raises[-1] > max(raises[:-1])


def test_with_every_module_active_more_raises_are_kept_while_the_head_ends_higher(planner):
    """Seed 14 once ended at 0.492 m (the other seeds 0.535-0.617 m): one last raise's optimum
    depends on where it starts. Further raises from where it ended, each kept only when the head
    ends higher by head_height_tol_m, lift it above 0.5 m."""
    plan = planner.plan(seed=14)
    tol = planner.cfg.head_height_tol_m
    last = [planner.chain.pose(st.q_end).head[2] for st in plan.stages
            if st.kind == "raise" and st.active_modules == 12]
    assert plan.final_head_height_m >= 0.5
    assert len(last) >= 2 and all(b > a + tol for a, b in zip(last, last[1:]))
    assert len(last) <= 1 + planner.cfg.max_final_cycles


def test_plan_checker_catches_a_zmp_outside_and_a_gap(planner):
    doc = plan_io.to_dict(planner.plan(max_active=2, seed=0))
    assert plan_io.problems(doc) == []
    bad = json.loads(json.dumps(doc))
    bad["samples"][3]["zmp_m"] = [5.0, 5.0]
    del bad["samples"][5:7]
    found = " ".join(plan_io.problems(bad))
    assert "outside the support polygon" in found and "gaps" in found


def test_lowering_returns_to_the_lying_posture_through_the_same_zmps(planner):
    plan = planner.plan(max_active=4, seed=0)
    down = lowering(plan)
    np.testing.assert_allclose(down.q_end, planner.chain.q_lying, atol=1e-12)
    doc = plan_io.to_dict(down)
    assert plan_io.problems(doc) == []
    up_zmp = [s["zmp_m"] for s in plan_io.to_dict(plan)["samples"]]
    np.testing.assert_allclose([s["zmp_m"] for s in doc["samples"]], up_zmp[::-1], atol=1e-9)


def test_cli_plan_writes_the_contract_and_figures(tmp_path):
    out = tmp_path / "p"
    assert cli.main(["scout", "plan", "--robot", "unified_snake", "--max-active", "2",
                     "--seed", "3", "--out", str(out)]) == 0
    doc = json.loads((out / "plan.json").read_text())
    assert doc["robot"] == "unified_snake" and len(doc["joint_names"]) == 16
    assert plan_io.problems(doc, 16, 18) == []
    assert (out / "zmp_stages.png").stat().st_size > 0 and (out / "head_height.png").is_file()


@pytest.mark.parametrize("argv, message", [
    (["--robot", "no_such_robot"], "unknown robot"),
    (["--robot", "unified_snake", "--height-m", "3"], "no plan reaches it"),
    (["--robot", "unified_snake", "--pipe=-0.3,0.27,0.05"], "the pipe is inside the lying robot"),
    (["--robot", "unified_snake", "--pipe", "1,2"], "expected X,Y,R"),
    (["--robot", "unified_snake", "--max-active", "40"], "--max-active 40"),
    (["--robot", "unified_snake", "--pipe=1e9,0,0.07"],
     "--pipe 1e9,0,0.07: the axis must be within 2 m of the tail in x and y, got x 1e+09"),
    (["--robot", "unified_snake", "--pipe=0.05,nan,0.07"], "--pipe 0.05,nan,0.07: X, Y and R must be finite"),
    (["--robot", "unified_snake", "--pipe=0.05,-0.1,5"], "--pipe 0.05,-0.1,5: R must be in (0, 0.5] m, got 5"),
    (["--robot", "unified_snake", "--pipe=1.5,1.5,0.07"],
     "--pipe 1.5,1.5,0.07: the axis is 2.12 m from the tail, beyond the 1.09 m length of unified_snake"),
    (["--robot", "unified_snake", "--seed", "-1"], "--seed -1: must be an integer in 0..4294967295"),
    (["--robot", "unified_snake", "--seed", "1.5"], "--seed 1.5: must be an integer in 0..4294967295"),
])
def test_cli_bad_options_one_message_exit_1(tmp_path, capsys, argv, message):
    assert cli.main(["scout", "plan", *argv, "--out", str(tmp_path / "x")]) == 1
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x" / "plan.json").exists()
