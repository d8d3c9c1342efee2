"""The command line's help: every option has a help string and shows its default; the long
commands report progress on stderr unless told not to."""
import argparse
import json

import pytest

from snake_autonomy import cli

from conftest import ROOT


def _options():
    """(parser, action) of every argument of every (sub-)command but --help and the command choosers."""
    parser = cli.build_parser(load_all=True)
    for p in cli.walk_parsers(parser):
        for action in p._actions:
            if not isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
                yield p, action


def test_every_subcommand_is_walked():
    progs = {p.prog for p in cli.walk_parsers(cli.build_parser(load_all=True))}
    for prog in ("snake_autonomy nav run", "snake_autonomy nav experiment", "snake_autonomy nav train-classifier",
                 "snake_autonomy scout run", "snake_autonomy gait-map", "snake_autonomy evaluate",
                 "snake_autonomy report", "snake_autonomy mission check", "snake_autonomy sim experiment"):
        assert prog in progs


def test_every_option_has_a_help_string():
    missing = [f"{p.prog} {'/'.join(a.option_strings) or a.dest}" for p, a in _options() if not a.help]
    assert missing == []


def test_every_option_with_a_default_shows_it_in_its_help():
    hidden = []
    for p, action in _options():
        if action.default is None or action.default is argparse.SUPPRESS:
            continue
        shown = p._get_formatter()._expand_help(action)
        if f"(default: {action.default})" not in shown:
            hidden.append(f"{p.prog} {'/'.join(action.option_strings) or action.dest}: {shown!r}")
    assert hidden == []


def test_formatted_help_of_nav_run_names_a_default(capsys):
    try:
        cli.main(["nav", "run", "--help"])
    except SystemExit as e:
        assert e.code == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "(default: 1200.0)" in out            # --time-limit
    assert "(default: depth)" in out             # --perception


def _nav_run(tmp_path, *extra):
    argv = ["nav", "run", "--world", str(ROOT / "config" / "worlds" / "one_obstacle.yaml"),
            "--time-limit", "3", "--out", str(tmp_path / "out"), *extra]
    assert cli.main(argv) == 0


def test_nav_run_reports_simulated_seconds_on_stderr(tmp_path, capsys):
    _nav_run(tmp_path)
    captured = capsys.readouterr()
    assert "sim s" in captured.err and "%|" in captured.err        # the bar, on stderr
    assert "%|" not in captured.out
    json.loads(captured.out.strip().splitlines()[-1])                # stdout still ends with the metrics


def test_nav_run_with_no_progress_prints_no_bar(tmp_path, capsys):
    _nav_run(tmp_path, "--no-progress")
    captured = capsys.readouterr()
    assert "%|" not in captured.err and "sim s" not in captured.err
    json.loads(captured.out.strip().splitlines()[-1])


@pytest.mark.parametrize("extra,bar", [((), True), (("--no-progress",), False)])
def test_nav_eval_perception_counts_its_rendered_scenes_on_stderr(capsys, extra, bar):
    assert cli.main(["nav", "eval-perception", "--scenes", "1", *extra]) == 0
    captured = capsys.readouterr()
    assert ("1/1" in captured.err and "scene" in captured.err and "%|" in captured.err) == bar, captured.err
    assert "%|" not in captured.out and "depth: precision" in captured.out
