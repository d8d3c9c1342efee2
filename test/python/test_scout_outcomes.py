"""`scout run` says how the run ended: metrics.json's `outcome` ("ok", "tipped", "missed_pipe",
"missed_height"), and an exit status of 3 with a one-line reason when the robot tipped in physics or
the head ended outside the pipe's bore or below the planned height (runs/scout_execute.verdict)."""
import json

import numpy as np
import pytest

from snake_autonomy import cli
from snake_autonomy.cli import scout as scout_cli
from snake_autonomy.planning.fbsr.build import build_planner
from snake_autonomy.planning.fbsr.config import ScoutConfig, default_path
from snake_autonomy.runs import scout_execute
from snake_autonomy.planning.fbsr import planner as fbsr_planner
from snake_autonomy.planning.fbsr.planner import Plan
from snake_autonomy.planning.fbsr.stage import Stage
from snake_autonomy.runs.scout_execute import Measured, verdict
from snake_autonomy.sim.config import servo_torque_limit_nm


def test_a_run_that_stayed_down_and_reached_the_bore_is_ok():
    """The base carrying 76 % of the weight: the head leans on the pipe's wall, no module planned in
    the air rests on the floor."""
    v = verdict(Measured(max_lift_m=0.001, longest_no_pressure_s=0.02, base_load_fraction=0.76, head_z_m=0.30,
                         target_z_m=0.31, head_to_axis_m=0.025, bore_limit_m=0.0446, mouth_m=0.25))
    assert (v.tipped, v.outcome, v.reason) == (False, "ok", "")
    assert verdict(Measured()).outcome == "ok"          # no pipe, no height given: nothing to miss


@pytest.mark.parametrize("measured, words", [
    (Measured(max_lift_m=0.150), "a base module lifted 150 mm off the floor (limit 20 mm)"),
    (Measured(longest_outside_s=0.3), "the centre of pressure left the contacts' polygon for 0.30 s (limit 0.1 s)"),
    (Measured(longest_no_pressure_s=0.2), "the floor carried no weight for 0.20 s (limit 0.1 s)"),
    (Measured(longest_com_outside_s=0.2),
     "the centre of mass left the polygon of the base's contacts for 0.20 s (limit 0.1 s)"),
    (Measured(base_load_fraction=0.71, air_load_fraction=0.29),
     "the floor carried 29 % of the weight on modules planned in the air (at most 10 %; the base 71 %)"),
    (Measured(air_load_fraction=float("nan")), "the floor carried nan % of the weight"),
])
def test_a_base_lift_a_lost_support_or_a_base_unloaded_is_tipped_with_the_figure_and_the_limit(measured, words):
    v = verdict(measured)
    assert v.tipped is True and v.outcome == "tipped"
    assert v.reason.startswith("the robot tipped: ") and words in v.reason


@pytest.mark.parametrize("measured", [Measured(longest_com_outside_s=0.1), Measured(air_load_fraction=0.1)])
def test_a_spell_or_a_load_at_its_limit_is_not_tipped(measured):
    assert verdict(measured).outcome == "ok"


def test_a_head_outside_the_bore_is_missed_pipe_with_the_distance_and_the_limit():
    v = verdict(Measured(head_to_axis_m=0.106, bore_limit_m=0.0446))
    assert (v.tipped, v.outcome) == (False, "missed_pipe")
    assert v.reason == "missed the pipe: the head ended 0.106 m from the pipe's axis, outside the bore " \
                       "(0.045 m: the pipe's radius less a module's radius)"


def test_a_head_on_the_axis_but_under_the_mouth_is_missed_pipe():
    v = verdict(Measured(head_z_m=0.21, head_to_axis_m=0.01, bore_limit_m=0.0446, mouth_m=0.25))
    assert v.outcome == "missed_pipe"
    assert v.reason == "missed the pipe: the head ended at 0.210 m, below the mouth (0.250 m)"


def test_a_head_at_a_nan_distance_is_not_in_the_bore():
    assert verdict(Measured(head_to_axis_m=float("nan"), bore_limit_m=0.0446)).outcome == "missed_pipe"


@pytest.mark.parametrize("head, outcome", [(0.571, "ok"), (0.569, "missed_height"), (float("nan"), "missed_height")])
def test_a_head_more_than_the_tolerance_below_the_plan_is_missed_height(head, outcome):
    v = verdict(Measured(head_z_m=head, target_z_m=0.6))
    assert v.outcome == outcome and v.tipped is False
    if outcome != "ok":
        assert v.reason.startswith("missed the height: the head ended at ") and "below the plan's 0.600 m" in v.reason


def test_tipping_is_the_outcome_when_both_happened_and_the_reason_names_both():
    v = verdict(Measured(max_lift_m=0.15, head_z_m=0.08, target_z_m=0.64, head_to_axis_m=0.2, bore_limit_m=0.0446))
    assert v.outcome == "tipped" and "lifted 150 mm" in v.reason and "missed the pipe" in v.reason
    assert "missed the height" in v.reason


def fake_run_plan(max_lift_m, head_to_axis_m=None):
    """run_plan as the CLI calls it, its physics replaced by the given figures."""
    def run(plan, sim_yaml, seed, pipe, period):
        bore = pipe.radius_m - plan.chain.radius_m if pipe is not None else None
        v = verdict(Measured(max_lift_m=max_lift_m, head_to_axis_m=head_to_axis_m, bore_limit_m=bore))
        metrics = {"tipped": v.tipped, "outcome": v.outcome, "cop_inside_fraction": 1.0,
                   "final_head_height_m": 0.1, "planned_head_height_m": 0.1, "max_torque_ratio": 0.2,
                   "active_modules": plan.active_modules}
        extra = {"head_xy_m": [0.0, 0.0], "max_base_lift_m": max_lift_m, "reason": v.reason}
        if pipe is not None:
            extra.update(head_to_pipe_axis_m=head_to_axis_m, bore_limit_m=bore)
        return {"metrics": metrics, "extra": extra}
    return run


@pytest.mark.parametrize("fake, pipe, outcome, status, words", [
    (fake_run_plan(0.0), [], "ok", 0, None),
    (fake_run_plan(0.150), [], "tipped", 3, "scout run: the robot tipped: a base module lifted 150 mm"),
    (fake_run_plan(0.0, head_to_axis_m=0.106), ["--pipe", "0.05,-0.10,0.07"], "missed_pipe", 3,
     "scout run: missed the pipe: the head ended 0.106 m from the pipe's axis, outside the bore (0.045 m"),
])
def test_cli_run_exit_status_and_metrics_outcome(tmp_path, capsys, monkeypatch, fake, pipe, outcome, status, words):
    monkeypatch.setattr(scout_cli, "run_plan", fake)
    # the planner takes the 2-module raise as in the pipe: the miss is physics' (faked)
    monkeypatch.setattr(fbsr_planner, "head_in_mouth", lambda *_a: True)
    out = tmp_path / "run"
    assert cli.main(["scout", "run", "--no-progress", "--robot", "unified_snake", "--max-active", "2", *pipe,
                     "--out", str(out)]) == status
    assert json.loads((out / "metrics.json").read_text())["outcome"] == outcome
    err = capsys.readouterr().err
    if words is None:
        assert err == ""
    else:
        assert words in err and len(err.strip().splitlines()) == 1


def test_cli_run_help_documents_the_exit_status(capsys):
    with pytest.raises(SystemExit):
        cli.main(["scout", "run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "exit status: 0 the run is ok; 1 bad options or files; 2 usage; 3 the robot tipped, missed the pipe or " \
           "ended below the planned height in physics" in text


def test_run_plan_records_the_outcome_of_a_plan_in_physics(root, monkeypatch):
    """The verdict run_plan writes comes from its monitor: a base lift over the limit is tipped."""
    planner = build_planner("unified_snake", torque_limit_nm=servo_torque_limit_nm())[0]
    plan = planner.plan(max_active=2, seed=0, restarts=False)
    real_call = scout_execute.Monitor.__call__

    def lifting(self, _t=None):
        real_call(self, _t)
        self.max_lift_m = max(self.max_lift_m, 0.150)
    monkeypatch.setattr(scout_execute.Monitor, "__call__", lifting)
    m = scout_execute.run_plan(plan, root / "config/sim.yaml", seed=0)["metrics"]
    assert m["tipped"] is True and m["outcome"] == "tipped"


def test_cli_run_of_a_plan_that_tips_in_physics_exits_3(tmp_path, capsys, monkeypatch):
    """A run whose monitor measures a base lift of 150 mm (injected: the planner's mass model is
    the plant's, so no plan it accepts is known to tip) ends with exit 3, metrics.json's tipped
    outcome and the reason on stderr."""
    real_call = scout_execute.Monitor.__call__

    def lifting(self, _t=None):
        real_call(self, _t)
        self.max_lift_m = max(self.max_lift_m, 0.150)
    monkeypatch.setattr(scout_execute.Monitor, "__call__", lifting)
    out = tmp_path / "tip"
    assert cli.main(["scout", "run", "--no-progress", "--robot", "unified_snake", "--max-active", "2", "--seed", "1",
                     "--out", str(out)]) == 3
    m = json.loads((out / "metrics.json").read_text())
    assert m["tipped"] is True and m["outcome"] == "tipped"
    err = capsys.readouterr().err.strip()
    assert err.startswith("scout run: the robot tipped: a base module lifted 1") and "mm off the floor" in err


def test_a_plan_that_lifts_twelve_modules_off_a_five_module_base_tips_in_physics(root):
    """A hand-made raise the planner would refuse (the pitch joint at the base's hinge lifts the whole
    active portion: the CoM goes far beyond the base) tips in physics; the CoP, a weighted mean of
    the contacts, stays inside them throughout, so only the base's lift, its load and the CoM
    against the base's own contacts can tell."""
    chain = build_planner("unified_snake", torque_limit_nm=servo_torque_limit_nm())[0].chain
    m = 12
    delta = np.zeros(m)
    delta[10] = 0.8
    plan = Plan(chain.robot.name, chain, [Stage("raise", m, chain.q_lying.copy(), delta, 3.0, chain.base_contacts(m))])
    assert plan.final_head_height_m > 0.4
    result = scout_execute.run_plan(plan, root / "config/sim.yaml", seed=0)
    m, extra = result["metrics"], result["extra"]
    assert m["tipped"] is True and m["outcome"] == "tipped"
    assert m["cop_inside_fraction"] > 0.99
    assert extra["max_base_lift_m"] > 0.05 and extra["max_stage_base_rise_m"] >= extra["max_base_lift_m"]
    assert extra["longest_com_outside_s"] > 1.0 and extra["base_load_fraction"] < 0.8
    assert extra["air_load_fraction"] > 0.2
    assert m["final_head_height_m"] < 0.1
    for words in ("lifted", "centre of mass left", "on modules planned in the air", "missed the height"):
        assert words in extra["reason"]


def test_a_plan_the_planner_made_holds_its_base_in_physics(root):
    """The figures of the verdict on a plan that does not tip: the resting modules carry the weight,
    the CoM stays inside the base's contacts all along."""
    planner = build_planner("unified_snake", torque_limit_nm=servo_torque_limit_nm())[0]
    result = scout_execute.run_plan(planner.plan(max_active=4, seed=0), root / "config/sim.yaml", seed=0)
    extra = result["extra"]
    assert result["metrics"]["outcome"] == "ok"
    assert extra["base_load_fraction"] == pytest.approx(1.0, abs=0.05) and extra["air_load_fraction"] < 0.01
    assert extra["min_com_margin_m"] > 0.01 and extra["longest_com_outside_s"] == 0.0
    assert 0.0 <= extra["max_stage_base_rise_m"] < scout_execute.BASE_GAP_M


def test_cli_refuses_a_pipe_the_head_does_not_get_into_with_where_it_ended(tmp_path, capsys):
    """Two active modules cannot lift the head 0.27 m into a mouth 0.25 m up: refused before physics,
    exit 1, the reason naming the pipe, the modules and where the last raise left the head."""
    out = tmp_path / "pipe"
    assert cli.main(["scout", "run", "--no-progress", "--robot", "unified_snake", "--max-active", "2",
                     "--pipe", "0.05,-0.10,0.07",
                     "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("scout run: --pipe 0.05,-0.1,0.07: no plan found puts the head into the pipe with at "
                          "most 2 active modules of unified_snake (the last raise ended ")
    clearance = ScoutConfig.from_yaml(default_path()).planner.pipe_clearance_m
    assert (f"the plan must end it within {0.0446 - clearance:.3f} m of the axis: the bore's 0.045 m less "
            f"pipe_clearance_m {clearance:g} m, at least 0.020 m above the mouth at 0.25 m") in err
    assert not (out / "metrics.json").exists()
