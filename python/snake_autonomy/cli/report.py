"""`snake_autonomy report BAG [--out DIR]`: rebuild a run's results folder from its bag.

Works on a bag left by a killed run (no index): a temporary copy is reindexed, the bag itself is
left untouched. Exit 0 and the written paths; 1, naming the bag, when it cannot be read or holds no
run (a bag cut before the run's start event).
"""
import json
import sys
from pathlib import Path

from snake_autonomy.runs.bag_io import RunBagError, report_from_bag


def add_arguments(parser):
    parser.add_argument("bag", metavar="BAG", help="the run's bag (results/<run>/run.bag)")
    parser.add_argument("--out", metavar="DIR", help="results folder (default: the bag's folder + _report)")
    parser.add_argument("--no-plots", action="store_true", help="metrics and CSVs only")


def main(args) -> int:
    bag = Path(args.bag)
    if not bag.is_file():
        print(f"report: {bag}: no such file", file=sys.stderr)
        return 1
    out = Path(args.out) if args.out else bag.parent / (bag.stem + "_report")
    try:
        paths = report_from_bag(bag, out, plots=not args.no_plots)
    except RunBagError as exc:
        print(f"report: {bag}: {exc}", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - any reading error is reported with the bag's name
        print(f"report: {bag}: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    metrics = json.loads(paths["metrics"].read_text())
    print(f"{bag}: outcome {metrics['outcome']}, {metrics['waypoints_reached']}/{metrics['num_waypoints']} "
          f"waypoints reached, {metrics['num_decisions']} decisions")
    for name, p in paths.items():
        print(f"  {name}: {p}")
    return 0
