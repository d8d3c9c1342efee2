"""The navigation experiment (runs/nav_experiment.py, `snake_autonomy nav experiment`): random
corridors are solvable by construction and reproducible; the command writes its table through the
sweep runner."""
import csv
import json
import math

from snake_autonomy.cli import main as cli_main
from snake_autonomy.cli.nav import parse_seeds
from snake_autonomy.runs.nav_experiment import min_gap_m, outcome_table, random_corridor, summarise

import pytest


def test_random_corridors_are_reproducible_solvable_and_block_the_straight_line():
    for k in range(30):
        w = random_corridor(k, body_width_m=0.09)
        assert w.to_dict() == random_corridor(k, body_width_m=0.09).to_dict()
        assert 1 <= len(w.obstacles) <= 3
        assert min_gap_m(w) >= 2 * 0.09 - 1e-9
        first = w.obstacles[0]
        assert abs(first.y_m) <= 0.05 and 0.45 <= first.x_m <= w.goal[0] - 0.35
        for ob in w.obstacles:   # the start and the goal stay clear
            assert ob.distance_m(*w.start[:2]) > 0.3 and ob.distance_m(*w.goal) > 0.2
    assert random_corridor(0).to_dict() != random_corridor(1).to_dict()


def test_parse_seeds():
    assert parse_seeds("0-4") == [0, 1, 2, 3, 4]
    assert parse_seeds("1,3") == [1, 3]
    with pytest.raises(ValueError, match="--seeds: expected FIRST-LAST"):
        parse_seeds("a-b")


def test_summarise_counts_success_only_without_collisions():
    base = {"robot": "cobra", "perception": "depth", "world": "w0", "stops_no_free_arc": 0, "time_s": 100.0}
    rows = [{**base, "goal_reached": True, "collisions": 0},
            {**base, "goal_reached": True, "collisions": 2, "world": "w1"},
            {**base, "goal_reached": False, "collisions": 0, "rolled_over": True, "world": "w2"}]
    s = summarise(rows)[0]
    assert s["runs"] == 3 and s["worlds"] == 3 and s["reached"] == 2
    assert s["success"] == pytest.approx(1 / 3) and s["runs_with_collision"] == 1 and s["collisions"] == 2
    assert s["rolled_over"] == 1 and s["mean_time_s"] == pytest.approx(100.0)


def test_summarise_counts_outcomes_and_contacts_by_mode():
    base = {"robot": "cobra", "perception": "depth", "world": "w0", "stops_no_free_arc": 0, "time_s": 300.0,
            "goal_reached": False, "collisions": 0}
    rows = [{**base, "outcome": "circling_goal", "closest_to_goal_m": 0.1},
            {**base, "outcome": "circling_goal", "world": "w1", "closest_to_goal_m": 0.3},
            {**base, "outcome": "reached_with_contact", "goal_reached": True, "collisions": 5,
             "contacts_follow": 4, "contacts_back_off": 1}]
    s = summarise(rows)[0]
    assert s["outcomes"]["circling_goal"] == 2 and s["outcomes"]["reached_with_contact"] == 1
    assert s["outcomes"]["success"] == 0
    assert s["contacts_by_mode"] == {"follow": 4, "turn_in_place": 0, "back_off": 1, "idle": 0}
    table = outcome_table([s])
    assert s["median_miss_m"] == pytest.approx(0.2)          # of the two not reached
    assert "| cobra | depth | 0 | 1 | 0 | 2 | 0 | 0 | 0.20 | 4 | 0 | 1 | 0 |" in table


def test_nav_experiment_writes_runs_summary_and_table(tmp_path):
    out = tmp_path / "exp"
    # contract only: 4 s of physics (the 2 s ramp and the first replan) per run, serial engine
    assert cli_main(["nav", "experiment", "--worlds", "1", "--seeds", "0", "--time-limit", "4",
                     "--engine", "serial", "--no-progress", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seeds"] == [0] and len(summary["worlds"]) == 1
    s = summary["summary"][0]
    assert s["runs"] == 1 and s["perception"] == "depth" and s["collisions"] == 0
    assert "| cobra | depth | 1 | 1 |" in (out / "table.md").read_text()
    assert "circling goal" in (out / "table.md").read_text()
    assert len((out / "runs.csv").read_text().splitlines()) == 2
    assert math.isfinite(summary["wall_s"])
    # every generated world as a world file: a row of runs.csv runs again alone, with its figures
    again = tmp_path / "again"
    assert cli_main(["nav", "run", "--world", str(out / "worlds" / "corridor_000.yaml"), "--seed", "0",
                     "--time-limit", "4", "--out", str(again)]) == 0
    row = next(csv.DictReader((out / "runs.csv").open()))
    metrics = json.loads((again / "metrics.json").read_text())
    for key in ("time_s", "path_length_m", "replans", "closest_to_goal_m", "outcome"):
        assert str(metrics[key]) == row[key], key


def test_nav_experiment_mono_needs_a_classifier(tmp_path, capsys):
    assert cli_main(["nav", "experiment", "--worlds", "1", "--perception", "both", "--engine", "serial",
                     "--out", str(tmp_path / "e")]) == 1
    assert "needs --classifier FILE" in capsys.readouterr().err


def test_the_default_time_limit_is_three_times_the_straight_line_time_at_the_robots_speed():
    from snake_autonomy.planning.rectilinear.config import NavConfig, nav_config_path
    from snake_autonomy.runs.nav_experiment import time_limit_s
    w = random_corridor(0)                                   # start (0, 0), goal (1.4, 0), disc 0.2 m
    assert time_limit_s(w, 0.01) == pytest.approx(3 * 1.2 / 0.01)
    assert time_limit_s(w, 0.01, factor=2.0) == pytest.approx(240.0)
    cobra = NavConfig.from_yaml(nav_config_path("cobra")).follower.speed_m_s
    chang = NavConfig.from_yaml(nav_config_path("chang_rectilinear")).follower.speed_m_s
    # the slower robot gets the longer limit (COBRA 567 s, the 12-link 321 s)
    assert time_limit_s(w, cobra) == pytest.approx(3 * 1.2 / cobra, abs=0.1) and 550 < time_limit_s(w, cobra) < 580
    assert 300 < time_limit_s(w, chang) < 340
    with pytest.raises(ValueError, match="speed_m_s and factor must be > 0, got 0.0, 3.0"):
        time_limit_s(w, 0.0)


def test_nav_experiment_records_each_worlds_time_limit_and_refuses_bad_ones(tmp_path, capsys):
    out = tmp_path / "exp"
    # auto with a tiny factor: 0.01 x 189 s = 1.9 s (the ramp only) for COBRA's world 0
    assert cli_main(["nav", "experiment", "--worlds", "1", "--seeds", "0", "--time-factor", "0.02",
                     "--engine", "serial", "--no-progress", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["time_limit"] == "auto" and summary["time_factor"] == 0.02
    assert summary["time_limits_s"]["corridor_000"] == pytest.approx(3.8, abs=0.05)
    row = next(csv.DictReader((out / "runs.csv").open()))
    assert float(row["time_limit_s"]) == pytest.approx(3.8, abs=0.05)
    assert float(row["time_s"]) == pytest.approx(3.8, abs=0.05)
    for args, message in ((["--time-limit", "soon"], "--time-limit: expected seconds or auto, got 'soon'"),
                          (["--time-limit", "-5"], "--time-limit: must be a finite number of seconds > 0, got -5.0"),
                          (["--time-limit", "inf"], "--time-limit: must be a finite number of seconds > 0, got inf"),
                          (["--time-limit", "60", "--time-factor", "2"],
                           "--time-factor 2.0: only with --time-limit auto"),
                          (["--time-factor", "0"], "--time-factor: must be a finite number > 0, got 0.0"),
                          (["--time-factor", "nan"], "--time-factor: must be a finite number > 0, got nan")):
        assert cli_main(["nav", "experiment", "--worlds", "1", "--engine", "serial", "--no-progress",
                         "--out", str(tmp_path / "bad")] + args) == 1
        assert message in capsys.readouterr().err


def test_experiment_tasks_take_one_time_limit_per_world():
    from snake_autonomy.runs.nav_experiment import experiment_tasks
    worlds = [random_corridor(0), random_corridor(1)]
    tasks = experiment_tasks(worlds, [0, 1], ["depth"], time_limits_s=[100.0, 200.0])
    assert [(t.world["name"], t.seed, t.time_limit_s) for t in tasks] == [
        ("corridor_000", 0, 100.0), ("corridor_000", 1, 100.0), ("corridor_001", 0, 200.0), ("corridor_001", 1, 200.0)]
    assert {t.time_limit_s for t in experiment_tasks(worlds, [0], ["depth"])} == {300.0}   # NavTask's default
    with pytest.raises(ValueError, match=r"time_limits_s: one per world expected \(2\), got 1"):
        experiment_tasks(worlds, [0], ["depth"], time_limits_s=[100.0])
