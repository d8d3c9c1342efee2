"""The FBSR planner for a robot named on the command line or in a mission: its model, config/scout.yaml's
parameters and posture, and the servos' torque limit (which the caller reads: config/sim.yaml's
servo.torque_limit_nm through sim.config.servo_torque_limit_nm)."""
from pathlib import Path

from snake_autonomy import _core

from ...paths import config_path, robot_yaml
from .config import ScoutConfig, default_path
from .planner import FbsrPlanner


def build_planner(robot_arg: str, config_arg=None, *, torque_limit_nm: float):
    """(planner, config) for a robot name or YAML; ValueError/FileNotFoundError with a message."""
    path = robot_yaml(robot_arg)
    if not Path(path).is_file():
        known = sorted(p.stem for p in config_path("robots").glob("*.yaml"))
        raise ValueError(f"--robot {robot_arg}: unknown robot (known: {', '.join(known)})")
    robot = _core.RobotModel.from_yaml(str(path))
    cfg = ScoutConfig.from_yaml(config_arg or default_path())
    return FbsrPlanner(robot, cfg.planner, cfg.posture(robot.name), torque_limit_nm), cfg
