"""The `snake_autonomy` command line: one entry point, subcommands in their own modules.

Each subcommand module defines ``add_arguments(parser)`` and ``main(args) -> int`` and is imported
only when its subcommand runs, so a broken or slow import in one never affects another.

No traceback reaches a user: a subcommand reports the input problems it knows (exit 1); anything that
still escapes it (a bad file refused by a loader, an out-of-memory, a bug) is printed here as one
line naming the command, exit 1. ``SNAKE_AUTONOMY_DEBUG=1`` re-raises it, with its traceback.
"""
import argparse
import importlib
import os
import sys

# subcommand -> (module, one-line help)
SUBCOMMANDS = {
    "gait": ("snake_autonomy.cli.gait", "run a gait open-loop through the core and plot it"),
    "mission": ("snake_autonomy.cli.mission", "check mission files"),
    "sim": ("snake_autonomy.cli.sim", "run missions on the simulated robot (no ROS)"),
    "evaluate": ("snake_autonomy.cli.evaluate", "evaluate a state estimate against ground truth"),
    "urdf": ("snake_autonomy.cli.urdf", "print the URDF generated from a robot description"),
    "nav": ("snake_autonomy.cli.nav",
            "navigation among obstacles (rectilinear gait, head camera): classifier, perception"),
    "gait-map": ("snake_autonomy.cli.gait_map",
                 "gait map: sweep amplitude and steering on Dask -> steady body velocity, fits, plot"),
    "report": ("snake_autonomy.cli.report", "rebuild a run's results folder from its bag"),
    "calibrate": ("snake_autonomy.cli.calibrate",
                  "steering offset (eq. 3.31) and heading offset, on the simulated robot or through ROS"),
    "scout": ("snake_autonomy.cli.scout", "raise the head stably (FBSR planner): plan, run in physics"),
}


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Every option's help ends with its default, except an option whose default is None (its help
    says what happens without it)."""

    def _get_help_string(self, action):
        if action.default is None:
            return action.help
        return super()._get_help_string(action)


def build_parser(chosen=None, load_all: bool = False) -> argparse.ArgumentParser:
    """The whole parser; only the chosen subcommand's module is imported (every one with load_all),
    so the others' options are absent. Every (sub-)parser gets HelpFormatter."""
    parser = argparse.ArgumentParser(
        prog="snake_autonomy",
        description="snake_autonomy: autonomy stack for modular snake robots")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module_name, help_text) in SUBCOMMANDS.items():
        sub_parser = sub.add_parser(name, help=help_text, description=help_text)
        if load_all or name == chosen:
            module = importlib.import_module(module_name)
            module.add_arguments(sub_parser)
            sub_parser.set_defaults(_main=module.main)
    for p in walk_parsers(parser):
        p.formatter_class = HelpFormatter
    return parser


def walk_parsers(parser: argparse.ArgumentParser):
    """parser and every parser under it (subcommands, their actions, ...), depth first."""
    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                yield from walk_parsers(child)


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    chosen = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(chosen)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    if not hasattr(args, "_main"):
        parser.error(f"unknown command {args.command!r}")
    try:
        return int(args._main(args) or 0)
    except KeyboardInterrupt:
        return 130
    except Exception as exc:  # noqa: BLE001 - the last guard: one line, never a traceback
        if os.environ.get("SNAKE_AUTONOMY_DEBUG"):
            raise
        print(f"snake_autonomy {args.command}: error: {one_line(exc)}", file=sys.stderr)
        return 1


def one_line(exc: BaseException) -> str:
    """The exception as one line: its message (an OSError with its file), else its type's name."""
    if isinstance(exc, OSError) and exc.filename:
        return f"{exc.filename}: {exc.strerror or exc}"
    if isinstance(exc, MemoryError):
        return "out of memory (input too large)"
    if isinstance(exc, RecursionError):
        return "input nested too deeply"
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if isinstance(exc, ValueError) else f"{type(exc).__name__}: {text}"

