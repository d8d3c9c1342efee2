"""`snake_autonomy urdf ROBOT`: print the URDF generated from a robot description (used by the
launch files for robot_description: the geometry lives in the robot YAML only)."""
import sys

from snake_autonomy import _core
from snake_autonomy.paths import robot_yaml


def add_arguments(parser):
    parser.add_argument("robot", nargs="?", default="cobra", help="robot name under config/robots/ or a YAML path")


def main(args) -> int:
    try:
        model = _core.RobotModel.from_yaml(str(robot_yaml(args.robot)))
    except ValueError as err:
        print(err, file=sys.stderr)
        return 1
    sys.stdout.write(_core.make_urdf(model))
    return 0
