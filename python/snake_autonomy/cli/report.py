"""`snake_autonomy report BAG|DIR [--out DIR]`: rebuild a run's results folder from its bag.

A mission run's bag gives the mission's metrics and figures (runs/results.py); a navigation run's
(nav_record_node, `sim.launch world:=FILE`) gives `snake_autonomy nav run`'s files (runs/nav_record.py).
DIR is a run's folder (its run.bag). Works on a bag left by a killed run (no index): a temporary
copy is reindexed, the bag itself is left untouched. Exit 0 and the written paths; 1, naming the
bag, when it cannot be read or holds no run (a bag cut before the run's start event).
"""
import json
import sys
from pathlib import Path

from snake_autonomy.runs.bag_io import RunBagError, report_from_bag, start_event
from snake_autonomy.runs.nav_record import KIND as NAV_KIND
from snake_autonomy.runs.nav_record import report_nav_bag
from snake_autonomy.runs.run_log import BAG_NAME


def add_arguments(parser):
    parser.add_argument("bag", metavar="BAG|DIR", help=f"the run's bag, or its folder (results/<run>/{BAG_NAME})")
    parser.add_argument("--out", metavar="DIR", help="results folder (default: the bag's folder + _report)")
    parser.add_argument("--no-plots", action="store_true", help="metrics and CSVs only (mission runs)")


def main(args) -> int:
    bag = Path(args.bag)
    if bag.is_dir():
        bag = bag / BAG_NAME
    if not bag.is_file():
        print(f"report: {bag}: no such file", file=sys.stderr)
        return 1
    out = Path(args.out) if args.out else bag.parent / (bag.stem + "_report")
    try:
        event = start_event(bag)
        if event is not None and event.get("kind") == NAV_KIND:
            return _navigation(bag, out)
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


def _navigation(bag: Path, out: Path) -> int:
    m = report_nav_bag(bag, out)
    print(f"{bag}: navigation run, outcome {m['outcome']}, goal reached {m['goal_reached']}, "
          f"{m['collisions']} contact(s), {m['replans']} replans, time {m['time_s']:.0f} s (record ended: {m['end']})")
    for p in sorted(out.iterdir()):
        print(f"  {p}")
    return 0
