"""`snake_autonomy evaluate` on rows that are not poses and on out-of-range options.

Rule: the documented tracking-loss markers (a zero quaternion: RTAB-Map's null pose; an Odometry
covariance at the loss threshold) are counted and reported as loss; anything else that is not a pose
(NaN/inf, a 1e308 position, a non-unit quaternion, a NaN stamp, stamps that decrease) is refused
whole, naming the file, the row and the value. A repeated stamp is kept with a warning, as evo keeps
it (real reference data has them). Before, NaN rows and inf quaternions passed as
"tracking loss", a NaN stamp was dropped, unsorted stamps were evaluated and a 1e308 row gave rmse inf
with exit 0.
"""
import re

import numpy as np
import pytest

import evaluation_data as data
from snake_autonomy.cli import main as cli_main
from snake_autonomy.evaluation import EvaluationError, EvaluationOptions
from snake_autonomy.evaluation.readers import trajectory_from_arrays

N = 30


def _rows(k_bad=None, bad=None):
    stamps = 1000.0 + 0.1 * np.arange(N)
    xyz = np.stack([0.01 * np.arange(N), np.zeros(N), np.zeros(N)], axis=1)
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (N, 1))
    if k_bad is not None:
        what, value = bad
        {"stamp": stamps, "xyz": xyz, "quat": quat}[what][k_bad] = value
    return stamps, xyz, quat


def _files(tmp_path, bad=None, k_bad=7):
    ref = data.write_tum(tmp_path / "ref.txt", *_rows())
    est = data.write_tum(tmp_path / "est.txt", *_rows(k_bad if bad else None, bad))
    return ref, est


def _run(args, capsys):
    rc = cli_main(["evaluate", *map(str, args)])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, out, err


@pytest.mark.parametrize("bad,message", [
    (("xyz", [np.nan, 0.0, 0.0]), "non-finite position [nan, 0.0, 0.0]"),
    (("quat", [0.0, 0.0, np.inf, 1.0]), "non-finite quaternion"),
    (("xyz", [1e308, 0.0, 0.0]), "position [1e+308, 0.0, 0.0] beyond +-100000 m"),
    (("quat", [0.0, 0.0, 1e200, 1e200]), "is not a unit quaternion (norm 1.41421e+200"),
    (("quat", [0.0, 0.0, 0.0, 2.0]), "is not a unit quaternion (norm 2"),
    (("stamp", np.nan), "the stamp is not a finite number"),
    (("stamp", 1000.55), "the stamp goes back from the previous one 1000.6"),
])
def test_rows_that_are_not_poses_are_refused(tmp_path, capsys, bad, message):
    ref, est = _files(tmp_path, bad, k_bad=7)
    rc, out, err = _run([ref, est], capsys)
    assert rc == 1, out
    assert str(est) in err and message in err and "pose 7 " in err, err


def test_a_repeated_stamp_is_kept_with_a_warning_as_evo_keeps_it(tmp_path, capsys):
    ref, est = _files(tmp_path, ("stamp", 1000.6), k_bad=7)
    rc, out, err = _run([ref, est], capsys)
    assert rc == 0 and re.search(r"pairs\s+30", out)
    assert f"warning: {est}: pose 7 " in err and "the stamp repeats the previous one (1 repeated stamps" in err


def test_a_zero_quaternion_is_a_counted_tracking_loss(tmp_path, capsys):
    ref, est = _files(tmp_path, ("quat", [0.0, 0.0, 0.0, 0.0]), k_bad=10)
    rc, out, _ = _run([ref, est], capsys)
    assert rc == 0
    assert re.search(r"pairs\s+29", out) and re.search(r"loss\s+1 intervals", out)


def test_arrays_follow_the_same_rules():
    stamps, xyz, quat = _rows(3, ("xyz", [np.nan, 0, 0]))
    with pytest.raises(EvaluationError, match="est: pose 3 .*non-finite position"):
        trajectory_from_arrays(stamps, xyz, quat, name="est")
    stamps, xyz, quat = _rows(3, ("quat", [0, 0, 0, 0]))
    assert trajectory_from_arrays(stamps, xyz, quat, name="est").dropped_poses == 1


@pytest.mark.parametrize("option,value,message", [
    ("--max-gap", "-5", "max_gap_s=-5.0"),
    ("--t-offset", "inf", "t_offset_s=inf"),
    ("--t-offset", "nan", "t_offset_s=nan"),
    ("--t-max-diff", "nan", "t_max_diff_s=nan"),
    ("--delta", "0", "delta=0.0"),
    ("--delta", "inf", "delta=inf"),
    ("--lost-covariance", "-1", "--lost-covariance: must be a positive number"),
])
def test_options_are_range_checked(tmp_path, capsys, option, value, message):
    ref, est = _files(tmp_path)
    rc, out, err = _run([ref, est, option, value], capsys)
    assert rc == 1 and message in err, err
    assert "nan" not in out


def test_option_ranges_in_the_library():
    with pytest.raises(EvaluationError) as info:
        EvaluationOptions(max_gap_s=-5, t_offset_s=float("inf"), delta=float("nan")).validate()
    assert all(t in str(info.value) for t in ("max_gap_s=-5", "t_offset_s=inf", "delta=nan"))
    EvaluationOptions(max_gap_s=0, t_offset_s=-1.7e9).validate()   # off, and a clock offset of an epoch


def test_outputs_that_cannot_be_written_are_one_line(tmp_path, capsys):
    ref, est = _files(tmp_path)
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    rc, _, err = _run([ref, est, "--plots", blocker / "plots"], capsys)
    assert rc == 1 and f"--plots: cannot create the folder {blocker / 'plots'}" in err
    assert len(err.strip().splitlines()) == 1
    rc, _, err = _run([ref, est, "--json", tmp_path], capsys)
    assert rc == 1 and "is a folder" in err
