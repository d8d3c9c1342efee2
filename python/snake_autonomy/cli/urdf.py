"""`snake_autonomy urdf ROBOT`: print the URDF generated from a robot description (used by the
launch files for robot_description: the geometry lives in the robot YAML only, the camera's mounting
in config/camera.yaml only)."""
import sys

from snake_autonomy import _core
from snake_autonomy.estimation import load_camera_calibration
from snake_autonomy.paths import config_path, robot_yaml


def add_arguments(parser):
    parser.add_argument("robot", nargs="?", default="cobra", help="robot name under config/robots/ or a YAML path")
    parser.add_argument("--camera", default=str(config_path("camera.yaml")), metavar="YAML",
                        help="camera calibration giving camera_in_head")
    parser.add_argument("--no-camera", action="store_true", help="leave the camera links out")
    parser.add_argument("--camera-name", default="camera",
                        help="prefix of the camera links: NAME_link, NAME_color_optical_frame")


def main(args) -> int:
    try:
        model = _core.RobotModel.from_yaml(str(robot_yaml(args.robot)))
        camera_in_head = None
        if not args.no_camera:
            camera_in_head = load_camera_calibration(args.camera).camera_in_head
    except (ValueError, OSError) as err:
        print(err, file=sys.stderr)
        return 1
    sys.stdout.write(_core.make_urdf(model, camera_in_head=camera_in_head, camera_name=args.camera_name))
    return 0
