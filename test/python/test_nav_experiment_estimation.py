"""The experiment's estimation table (runs/nav_experiment.py): which pose source and depth the runs
had, how far their pose was from the truth and how long tracking was lost."""
import math

from snake_autonomy.runs.nav_experiment import estimation_table, summarise


def test_the_estimation_table_summarises_pose_error_and_lost_tracking():
    base = {"robot": "cobra", "perception": "depth", "world": "w0", "stops_no_free_arc": 0, "time_s": 300.0,
            "goal_reached": False, "collisions": 0, "pose_source": "vio", "depth_model": "noisy"}
    rows = [{**base, "pose_error_xy_rmse_m": 0.10, "pose_error_xy_max_m": 0.20, "tracking_lost_s": 2.5},
            {**base, "world": "w1", "pose_error_xy_rmse_m": 0.30, "pose_error_xy_max_m": 0.45, "tracking_lost_s": 1.0}]
    s = summarise(rows)[0]
    assert s["pose_sources"] == ["vio"] and s["depth_models"] == ["noisy"]
    assert math.isclose(s["pose_error_xy_rmse_m"], 0.20) and s["pose_error_xy_max_m"] == 0.45
    assert s["tracking_lost_s"] == 3.5
    assert "| cobra | depth | vio | noisy | 0.200 | 0.450 | 3.5 |" in estimation_table([s])


def test_rows_without_estimation_figures_show_dashes():
    rows = [{"robot": "cobra", "perception": "mono", "world": "w0", "stops_no_free_arc": 0, "time_s": 1.0,
             "goal_reached": True, "collisions": 0}]
    assert "| cobra | mono | - | - | - | - | 0.0 |" in estimation_table(summarise(rows))
