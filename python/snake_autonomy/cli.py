"""The `snake_autonomy` command line: one entry point, subcommands in their own modules.

Each subcommand module defines ``add_arguments(parser)`` and ``main(args) -> int`` and is imported
only when its subcommand runs, so a broken or slow import in one never affects another.
"""
import argparse
import importlib
import sys

# subcommand -> (module, one-line help)
SUBCOMMANDS = {
    "gait": ("snake_autonomy.gait_cli", "run a gait open-loop through the core and plot it"),
    "mission": ("snake_autonomy.missions.cli", "check mission files"),
    "sim": ("snake_autonomy.sim.cli", "run missions on the simulated robot (no ROS)"),
    "evaluate": ("snake_autonomy.evaluation.cli", "evaluate a state estimate against ground truth"),
    "urdf": ("snake_autonomy.urdf_cli", "print the URDF generated from a robot description"),
    "report": ("snake_autonomy.experiments.cli", "rebuild a run's results folder from its bag"),
    "scout": ("snake_autonomy.planning.fbsr.cli", "raise the head stably (FBSR planner): plan, run in physics"),
}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="snake_autonomy",
        description="snake_autonomy: autonomy stack for modular snake robots")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    argv = list(sys.argv[1:] if argv is None else argv)
    chosen = next((a for a in argv if not a.startswith("-")), None)
    for name, (module_name, help_text) in SUBCOMMANDS.items():
        sub_parser = sub.add_parser(name, help=help_text, description=help_text)
        if name == chosen:
            module = importlib.import_module(module_name)
            module.add_arguments(sub_parser)
            sub_parser.set_defaults(_main=module.main)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    if not hasattr(args, "_main"):
        parser.error(f"unknown command {args.command!r}")
    return int(args._main(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
