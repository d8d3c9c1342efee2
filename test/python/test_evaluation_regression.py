"""Regression on real data: `snake_autonomy evaluate` reproduces evo's own command line to 1e-6.

evo_ape / evo_rpe run in the test (--save_results zip, read back with evo's loader) on the same inputs
and options; each evo call costs ~0.5 s, so the cases are few and cover: SE(3) on TUM files, Sim(3)
on a monocular keyframe file, the EuRoC CSV, the ROS 1 bag, origin alignment and RPE in metres.
"""
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from snake_autonomy.cli import main as cli_main

STATS = ("max", "mean", "median", "min", "rmse", "sse", "std")


def _evo_tool(name: str) -> str:
    local = Path(sys.executable).parent / name
    found = str(local) if local.exists() else shutil.which(name)
    if not found:
        pytest.skip(f"{name} (PyPI evo) is not installed")
    return found


def _evo(tool, args, tmp_path):
    from evo.tools import file_interface

    zip_path = tmp_path / f"{tool}.zip"
    cmd = [_evo_tool(tool), *args, "--save_results", str(zip_path), "--no_warnings", "--silent"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    res = file_interface.load_res_file(str(zip_path))
    return res.stats, len(res.np_arrays["error_array"])


def _ours(args, tmp_path):
    out = tmp_path / "ours.json"
    assert cli_main(["evaluate", *args, "--json", str(out), "--quiet"]) == 0
    return json.loads(out.read_text())


def _assert_same(ours, evo_stats, evo_pairs):
    for key in STATS:
        assert ours[key] == pytest.approx(evo_stats[key], abs=1e-6, rel=0), key
    assert ours["pairs"] == evo_pairs
    assert ours["excluded_pairs"] == 0


CASES = {
    # id: (evo tool, evo args, our args) -- file names relative to data/trajectories
    "tum-se3": ("evo_ape", ["tum", "{fr1_gt}", "{fr1_rgbd}", "-a"],
                ["{fr1_gt}", "{fr1_rgbd}", "--align", "se3"]),
    "tum-sim3-mono-kf": ("evo_ape", ["tum", "{fr2_gt}", "{fr2_kf}", "-as", "--t_max_diff", "0.02"],
                         ["{fr2_gt}", "{fr2_kf}", "--align", "sim3", "--t-max-diff", "0.02"]),
    "euroc-se3": ("evo_ape", ["euroc", "{v102_gt}", "{v102}", "-a"],
                  ["{v102_gt}", "{v102}", "--align", "se3"]),
    "bag-se3": ("evo_ape", ["bag", "{bag}", "groundtruth", "S-PTAM", "-a"],
                ["{bag}", "{bag}", "--ref-topic", "groundtruth", "--est-topic", "S-PTAM", "--align", "se3"]),
    "tum-origin-angle": ("evo_ape", ["tum", "{fr1_gt}", "{fr1_rgbd}", "--align_origin", "-r", "angle_deg"],
                         ["{fr1_gt}", "{fr1_rgbd}", "--align", "origin", "--relation", "angle_deg"]),
    "rpe-metres-angle": ("evo_rpe", ["tum", "{fr1_gt}", "{fr1_rgbd}", "-a", "--delta", "0.1", "--delta_unit",
                                     "m", "-r", "angle_deg"],
                         ["{fr1_gt}", "{fr1_rgbd}", "--metric", "rpe", "--align", "se3", "--delta", "0.1",
                          "--delta-unit", "m", "--relation", "angle_deg"]),
    "rpe-frames-sim3-mono-kf": ("evo_rpe", ["tum", "{fr2_gt}", "{fr2_kf}", "-as", "--delta", "2",
                                            "--t_max_diff", "0.02"],
                                ["{fr2_gt}", "{fr2_kf}", "--metric", "rpe", "--align", "sim3", "--delta", "2",
                                 "--t-max-diff", "0.02"]),
}


@pytest.fixture(scope="module")
def files(shared_dir):
    d = shared_dir / "data" / "trajectories"
    names = {"fr1_gt": "freiburg1_xyz-groundtruth.txt", "fr1_rgbd": "freiburg1_xyz-rgbdslam.txt",
             "fr1_kf": "freiburg1_xyz-ORB_kf_mono.txt", "fr2_gt": "fr2_desk_groundtruth.txt",
             "fr2_kf": "fr2_desk_ORB_kf_mono.txt", "v102_gt": "V102_groundtruth.csv", "v102": "V102.txt",
             "bag": "ROS_example.bag"}
    paths = {k: str(d / v) for k, v in names.items()}
    missing = [p for p in paths.values() if not Path(p).exists()]
    if missing:
        pytest.skip(f"reference data missing: {missing}")
    return paths


@pytest.mark.parametrize("case", list(CASES))
def test_statistics_equal_evo_command_line(case, files, tmp_path):
    tool, evo_args, our_args = CASES[case]
    evo_stats, evo_pairs = _evo(tool, [a.format(**files) for a in evo_args], tmp_path)
    ours = _ours([a.format(**files) for a in our_args], tmp_path)
    _assert_same(ours, evo_stats, evo_pairs)
    assert evo_pairs >= 20  # a real comparison, not a handful of pairs


def test_bag_topics_listed_when_missing(files, capsys):
    rc = cli_main(["evaluate", files["bag"], files["bag"], "--ref-topic", "groundtruth",
                   "--est-topic", "/rtabmap/odom"])
    err = capsys.readouterr().err
    assert rc == 1
    for topic in ("groundtruth", "ORB-SLAM", "S-PTAM"):
        assert topic in err
    assert "Traceback" not in err
