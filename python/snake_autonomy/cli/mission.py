"""`snake_autonomy mission check FILE...`: validate mission files before anything moves.

Exit 0 and a summary per file when every file is valid; exit 1 and every problem of every bad file
otherwise. FILE may also be the name of a provided mission (config/missions/NAME.yaml).
`snake_autonomy mission list` prints the provided missions.
"""
import sys

from snake_autonomy.missions.mission import MISSIONS_DIR, MissionError, gait_library_names, load_defaults, load_mission


def add_arguments(parser):
    sub = parser.add_subparsers(dest="mission_command", metavar="ACTION")
    check = sub.add_parser("check", help="validate mission files; list every problem")
    check.add_argument("files", nargs="+", metavar="FILE", help="mission YAML file or provided mission name")
    check.add_argument("--gaits", metavar="GAITS_YAML", help="gait library to check gait names against "
                       "(default: config/gaits.yaml)")
    check.add_argument("--defaults", metavar="TRACKER_YAML", help="tracker defaults (default: config/tracker.yaml)")
    sub.add_parser("list", help="list the provided missions")


def main(args) -> int:
    if args.mission_command == "list":
        for path in sorted(MISSIONS_DIR.glob("*.yaml")):
            print(path.stem)
        return 0
    if args.mission_command != "check":
        print("usage: snake_autonomy mission {check FILE...|list}", file=sys.stderr)
        return 2
    try:
        defaults = load_defaults(args.defaults)
    except (MissionError, OSError) as exc:
        print(f"tracker defaults: {exc}", file=sys.stderr)
        return 1
    try:
        library = gait_library_names(args.gaits)
    except (MissionError, OSError) as exc:
        print(f"gait library: {exc}", file=sys.stderr)
        return 1
    failed = 0
    for f in args.files:
        try:
            mission = load_mission(f, defaults=defaults, gait_library=library)
        except MissionError as exc:
            failed += 1
            print(f"INVALID {exc}", file=sys.stderr)
            continue
        print(f"OK {mission.source}\n{mission.summary()}")
    return 1 if failed else 0
