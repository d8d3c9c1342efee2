"""Tracking loss and segments on a synthetic logger bag (written with rosbag, see evaluation_data.py):
losses are found, kept out of the statistics, and the error is split per leg, gait and mode."""
import json
import re

import numpy as np
import pytest

import evaluation_data as data
from snake_autonomy.evaluation import (EvaluationOptions, evaluate, load_trajectory, read_tracking_status,
                                       write_outputs)
from snake_autonomy.evaluation.tracking_loss import (LossInterval, gap_intervals, intervals_from_mask,
                                                     points_in_loss, spans_in_loss)


@pytest.fixture(scope="module")
def run_bag(tmp_path_factory):
    return data.write_run_bag(tmp_path_factory.mktemp("bag") / "run.bag")


@pytest.fixture(scope="module")
def result(run_bag):
    ref = load_trajectory(run_bag, "bag", "/optitrack/head")
    est = load_trajectory(run_bag, "bag", "/rtabmap/odom")
    return evaluate(ref, est, EvaluationOptions(), status=read_tracking_status(run_bag))


def test_odometry_losses_are_read_from_covariance_and_null_poses(run_bag):
    est = load_trajectory(run_bag, "bag", "rtabmap/odom")  # with or without the leading slash
    assert est.dropped_poses == 11 + 1  # 112.0-113.0 s (covariance 9999) and the null pose at 125 s
    kinds = {iv.kind: iv for iv in est.loss_intervals}
    assert set(kinds) == {"covariance", "null"}
    assert (kinds["covariance"].start_s, kinds["covariance"].end_s) == pytest.approx((111.9, 113.1))
    assert (kinds["null"].start_s, kinds["null"].end_s) == pytest.approx((124.9, 125.1))
    assert est.traj.num_poses == data.N - 30 - 12


def test_loss_pairs_are_excluded_and_statistics_are_those_of_the_rest(result):
    kinds = sorted(iv.kind for iv in result.loss_intervals)
    assert kinds == ["covariance", "gap", "null", "pose_stale"]
    gap = next(iv for iv in result.loss_intervals if iv.kind == "gap")
    assert (gap.start_s, gap.end_s) == pytest.approx((114.9, 118.0))
    assert result.excluded_pairs == data.EXPECTED_EXCLUDED
    assert result.pairs == sum(data.EXPECTED_PAIRS.values())
    errors = np.concatenate([np.full(n, data.LEG_ERRORS[leg]) for leg, n in data.EXPECTED_PAIRS.items()])
    assert result.stats["rmse"] == pytest.approx(np.sqrt(np.mean(errors ** 2)), abs=1e-9)
    assert result.stats["mean"] == pytest.approx(errors.mean(), abs=1e-9)
    assert result.stats["max"] == pytest.approx(0.3, abs=1e-9)
    assert not np.any((result.stamps_s > 121.0) & (result.stamps_s < 123.0))


def test_keep_loss_puts_the_stale_pairs_back(run_bag):
    ref = load_trajectory(run_bag, "bag", "/optitrack/head")
    est = load_trajectory(run_bag, "bag", "/rtabmap/odom")
    kept = evaluate(ref, est, EvaluationOptions(exclude_loss=False), status=read_tracking_status(run_bag))
    assert kept.excluded_pairs == 0
    assert kept.pairs == sum(data.EXPECTED_PAIRS.values()) + data.EXPECTED_EXCLUDED


def test_segments_per_leg_gait_and_mode(result):
    legs = {g["label"]: g for g in result.segments["leg"]}
    assert list(legs) == ["waypoint 0", "waypoint 1", "done"]
    for leg, n in data.EXPECTED_PAIRS.items():
        assert legs[leg]["pairs"] == n
        assert legs[leg]["stats"]["mean"] == pytest.approx(data.LEG_ERRORS[leg], abs=1e-9)
        assert legs[leg]["stats"]["std"] == pytest.approx(0.0, abs=1e-9)
    gaits = {g["label"]: g for g in result.segments["gait"]}
    assert gaits["rolling"]["pairs"] == data.EXPECTED_PAIRS["waypoint 1"]
    n0, n2 = data.EXPECTED_PAIRS["waypoint 0"], data.EXPECTED_PAIRS["done"]
    assert gaits["sidewind"]["pairs"] == n0 + n2  # two separate legs, one gait
    assert gaits["sidewind"]["stats"]["mean"] == pytest.approx((0.1 * n0 + 0.2 * n2) / (n0 + n2), abs=1e-9)
    modes = {g["label"]: g["pairs"] for g in result.segments["mode"]}
    assert set(modes) == {"sidewind", "NEAR turn"}
    assert sum(modes.values()) == result.pairs
    assert [s[2] for s in result.segment_spans["leg"]] == ["waypoint 0", "waypoint 1", "done"]


def test_tf_child_frame_resolves_to_the_root_of_its_tree(run_bag):
    est = load_trajectory(run_bag, "bag", "/tf:base_link")
    assert est.name.endswith("/tf:map.base_link")
    ref = load_trajectory(run_bag, "bag", "/optitrack/head")
    res = evaluate(ref, est, EvaluationOptions(max_gap_s=0))
    # TF is the clean estimate: the per-leg offsets, no covariance/null losses
    assert res.stats["min"] == pytest.approx(0.1, abs=1e-6)
    assert res.stats["max"] == pytest.approx(0.3, abs=1e-6)
    assert res.excluded_pairs == 0


def test_outputs_json_plots_and_one_page_report(result, tmp_path):
    paths = write_outputs(result, tmp_path / "eval")
    magic = {".png": b"\x89PNG", ".pdf": b"%PDF", ".json": b"{"}
    for name in ("json", "xy", "xyz", "axis_error", "error", "report_pdf", "report_png"):
        path = paths[name]
        with open(path, "rb") as f:
            assert f.read(4).startswith(magic[path[path.rindex("."):]]), path
    doc = json.loads(open(paths["json"]).read())
    for key in ("max", "mean", "median", "min", "rmse", "sse", "std", "pairs"):
        assert key in doc
    assert doc["pairs"] == result.pairs and doc["excluded_pairs"] == data.EXPECTED_EXCLUDED
    assert {iv["kind"] for iv in doc["loss_intervals"]} == {"covariance", "gap", "null", "pose_stale"}
    assert [g["label"] for g in doc["segments"]["leg"]] == ["waypoint 0", "waypoint 1", "done"]
    pdf = open(paths["report_pdf"], "rb").read()
    assert len(re.findall(rb"/Type\s*/Page(?![s\w])", pdf)) == 1  # one page


def test_error_plot_shades_every_loss_interval(result):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgb

    from snake_autonomy.evaluation import plots

    fig, ax = plt.subplots()
    plots.plot_error(ax, result)
    red = [p for p in ax.patches if np.allclose(to_rgb(p.get_facecolor()), to_rgb(plots.LOSS_COLOR))]
    plt.close(fig)
    assert len(red) == len([iv for iv in result.loss_intervals if iv.end_s > iv.start_s])


def test_interval_rules():
    stamps = np.arange(10.0)
    lost = np.zeros(10, dtype=bool)
    lost[[0, 4, 5, 9]] = True
    ivs = intervals_from_mask(stamps, lost, "null")
    assert [(iv.start_s, iv.end_s) for iv in ivs] == [(0.0, 1.0), (3.0, 6.0), (8.0, 9.0)]
    assert [(g.start_s, g.end_s) for g in gap_intervals([0, 0.1, 0.2, 2.5, 2.6], None)] == [(0.2, 2.5)]
    assert gap_intervals([0, 0.1, 0.2, 2.5, 2.6], 0) == []
    assert gap_intervals(np.arange(0, 30, 0.5), None) == []  # 0.5 s keyframes: not a loss (auto)
    iv = [LossInterval(3.0, 6.0, "null")]
    assert points_in_loss([3.0, 4.0, 6.0], iv).tolist() == [False, True, False]
    assert spans_in_loss([2.0, 3.0, 6.0], [3.0, 6.0, 7.0], iv).tolist() == [False, True, False]


def test_cli_reads_segments_from_the_estimate_bag(run_bag, tmp_path, capsys):
    from snake_autonomy.cli import main as cli_main

    out_json = tmp_path / "stats.json"
    rc = cli_main(["evaluate", run_bag, run_bag, "--ref-topic", "/optitrack/head", "--est-topic",
                   "/rtabmap/odom", "--segment-by", "leg", "--json", str(out_json)])
    out = capsys.readouterr().out
    assert rc == 0
    assert re.search(r"waypoint 1\s+59\s+0\.3000\s+0\.3000", out)
    assert "gait" not in json.loads(out_json.read_text())["segments"]  # only the asked key
