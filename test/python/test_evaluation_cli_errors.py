"""Every user error of `snake_autonomy evaluate` is one clear message and exit 1, never a traceback."""
import re
import subprocess
import sys

import numpy as np
import pytest

import evaluation_data as data
from snake_autonomy.cli import main as cli_main
from snake_autonomy.evaluation import EvaluationError, EvaluationOptions


def _stamps(n=50, t0=1000.0, dt=0.1):
    return t0 + dt * np.arange(n)


def _tum(path, stamps, shift=(0.0, 0.0, 0.0)):
    u = np.linspace(0, 3, len(stamps))
    xyz = np.stack([np.cos(u), np.sin(u), 0.1 * u], axis=1) + shift
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (len(stamps), 1))
    return data.write_tum(path, stamps, xyz, quat)


def _run(args, capsys):
    rc = cli_main(["evaluate", *map(str, args)])
    out, err = capsys.readouterr()
    assert "Traceback" not in err + out
    return rc, out, err


def test_missing_file(tmp_path, capsys):
    ref = _tum(tmp_path / "ref.txt", _stamps())
    rc, _, err = _run([ref, tmp_path / "nope.txt"], capsys)
    assert rc == 1
    assert "nope.txt" in err and "no such file" in err


def test_unreadable_tum_and_bag(tmp_path, capsys):
    ref = _tum(tmp_path / "ref.txt", _stamps())
    bad = tmp_path / "bad.txt"
    bad.write_text("1.0 2.0 3.0\nnot a trajectory\n")
    rc, _, err = _run([ref, bad], capsys)
    assert rc == 1 and "cannot read" in err and "TUM" in err
    junk_bag = tmp_path / "junk.bag"
    junk_bag.write_bytes(b"\x00garbage" * 50)
    rc, _, err = _run([junk_bag, ref, "--ref-topic", "/x"], capsys)
    assert rc == 1 and "cannot read" in err and "bag" in err


def test_missing_topic_lists_the_topics_in_the_bag(tmp_path, capsys):
    bag = data.write_run_bag(tmp_path / "run.bag", with_tf=False)
    rc, _, err = _run([bag, bag, "--ref-topic", "/optitrack/head", "--est-topic", "/vins/odom"], capsys)
    assert rc == 1
    assert "/vins/odom" in err
    assert "/optitrack/head [geometry_msgs/PoseStamped]" in err and "/rtabmap/odom [nav_msgs/Odometry]" in err
    rc, _, err = _run([bag, bag, "--ref-topic", "/optitrack/head", "--est-topic", "/tracking_status"], capsys)
    assert rc == 1 and "not a pose" in err


def test_no_matching_stamps_names_a_window_that_does_match(tmp_path, capsys):
    ref = _tum(tmp_path / "ref.txt", _stamps())
    est = _tum(tmp_path / "est.txt", _stamps(t0=1000.0 - 37.25))  # another clock: 37.25 s behind
    rc, _, err = _run([ref, est], capsys)
    assert rc == 1
    assert "no matching timestamps" in err
    offset = re.search(r"--t-offset (-?[0-9.]+) lines up", err)
    assert offset and float(offset.group(1)) == pytest.approx(37.25)
    rc, out, err = _run([ref, est, "--t-offset", offset.group(1)], capsys)
    assert rc == 0 and re.search(r"pairs\s+50", out)
    # a small constant lag: the suggested --t-max-diff matches
    est2 = _tum(tmp_path / "est2.txt", _stamps(t0=1000.0 + 0.033))
    rc, _, err = _run([ref, est2], capsys)
    window = re.search(r"--t-max-diff ([0-9.e-]+) matches at least one pair", err)
    assert rc == 1 and window and 0.033 <= float(window.group(1)) < 0.04
    rc, _, _ = _run([ref, est2, "--t-max-diff", window.group(1)], capsys)
    assert rc == 0


@pytest.mark.parametrize("align", ["se3", "sim3", "yaw"])
def test_fewer_than_three_pairs_for_alignment(tmp_path, capsys, align):
    ref = _tum(tmp_path / "ref.txt", _stamps())
    est = _tum(tmp_path / "est.txt", np.array([1000.0, 1000.5, 1100.0, 1200.0]))  # 2 stamps match
    rc, _, err = _run([ref, est, "--align", align], capsys)
    assert rc == 1
    assert "at least 3 matched pairs, found 2" in err
    rc, out, _ = _run([ref, est, "--align", "none"], capsys)  # without alignment 2 pairs are fine
    assert rc == 0 and re.search(r"pairs\s+2", out)


def test_bag_without_topic_and_bad_options(tmp_path, capsys):
    bag = data.write_run_bag(tmp_path / "run.bag", with_tf=False, with_status=False)
    rc, _, err = _run([bag, bag, "--est-topic", "/rtabmap/odom"], capsys)
    assert rc == 1 and "name the topic" in err and "/optitrack/head" in err
    with pytest.raises(EvaluationError) as info:
        EvaluationOptions(metric="xyz", delta=1.5, t_max_diff_s=-1).validate()
    message = str(info.value)
    assert "metric='xyz'" in message and "delta=1.5" in message and "t_max_diff_s=-1" in message


def test_rosrun_script_exit_codes(root, tmp_path):
    """scripts/evaluate (rosrun snake_autonomy evaluate) as a process: 0 with the table, 1 on error."""
    ref = _tum(tmp_path / "ref.txt", _stamps())
    est = _tum(tmp_path / "est.txt", _stamps(), shift=(0.0, 0.0, 0.05))
    ok = subprocess.run([sys.executable, str(root / "scripts" / "evaluate"), ref, est],
                        capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr
    assert re.search(r"rmse\s+0\.050000", ok.stdout)
    bad = subprocess.run([sys.executable, str(root / "scripts" / "evaluate"), ref, str(tmp_path / "none.txt")],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 1 and "no such file" in bad.stderr and "Traceback" not in bad.stderr
