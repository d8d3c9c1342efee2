"""Progress of the long commands without a bar of their own before: `scout plan` / `scout run` count
the planner's stages and `nav ros-experiment` its runs on stderr; --no-progress prints none, and
stdout is the same either way."""
import re

import pytest

from snake_autonomy import cli
from snake_autonomy.runs import nav_ros_experiment

OK = {"goal_reached": True, "collisions": 0, "time_s": 30.0, "end": "goal_reached"}


def _fake_ros(world, world_file, seed, limit, run_dir, *rest):
    return {**OK, "wall_s": 1.0, "shutdown": "sigint", "shutdown_s": 0.1, "survivors": []}


def _fake_batch(world, seed, limit, run_dir, *rest):
    return {**OK, "time_from_move_s": 29.0, "outcome": "success", "wall_s": 1.0}


def _without_times(text):
    """stdout with its wall-clock seconds blanked (they differ between two runs)."""
    return re.sub(r"\d+(\.\d+)? s\b", "T s", text)


@pytest.fixture
def ros_experiment(tmp_path, root, monkeypatch, capsys):
    """nav ros-experiment on one world x two seeds, the ROS and batch runs stubbed: (out, err) of a run
    with the given extra options."""
    monkeypatch.setattr(nav_ros_experiment, "run_ros", _fake_ros)
    monkeypatch.setattr(nav_ros_experiment, "run_batch", _fake_batch)

    def run(*extra):
        out = tmp_path / f"out{len(extra)}"
        assert cli.main(["nav", "ros-experiment", "--world-files", str(root / "test/ros/worlds/sim_nav.yaml"),
                         "--seeds", "0,1", "--time-limit", "60", *extra, "--out", str(out)]) == 0
        captured = capsys.readouterr()
        return captured.out, captured.err
    return run


def test_ros_experiment_counts_its_runs_on_stderr_and_not_with_no_progress(ros_experiment):
    out_bar, err_bar = ros_experiment()
    out_quiet, err_quiet = ros_experiment("--no-progress")
    assert "2/2" in err_bar and "run" in err_bar and "%|" in err_bar, err_bar
    assert "%|" not in err_quiet and "2/2" not in err_quiet
    assert "%|" not in out_bar and "2 runs in" in out_bar
    assert _without_times(out_bar).replace("out0", "OUT") == _without_times(out_quiet).replace("out1", "OUT")


@pytest.mark.parametrize("extra,bar", [((), True), (("--no-progress",), False)])
def test_scout_plan_counts_the_planned_stages_on_stderr(tmp_path, capsys, extra, bar):
    assert cli.main(["scout", "plan", "--robot", "unified_snake", "--max-active", "2", "--seed", "3",
                     *extra, "--out", str(tmp_path / "p")]) == 0
    captured = capsys.readouterr()
    counted = re.search(r"scout plan: planning: (\d+)stage", captured.err)
    assert (counted is not None and "raise" in captured.err) == bar, captured.err
    if bar:   # the bar's count is the plan's stages, as stdout reports them
        stages = int(re.search(r"(\d+) stages", captured.out).group(1))
        assert int(re.findall(r"planning: (\d+)stage", captured.err)[-1]) == stages
    assert "stage/s" not in captured.out and captured.out.startswith("unified_snake: ")
