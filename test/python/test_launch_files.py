"""Launch files: every arg documented; defaults that keep two clones apart (the pty of the simulated
bus and the results folder under the clone or $ROS_HOME, never a shared /tmp path); the URDF and
/use_sim_time parameters. Parameters are resolved by roslaunch itself (--dump-params: no master,
nothing started, but robot_description's command runs)."""
import os
import subprocess
import xml.etree.ElementTree as ET

import pytest
import yaml

LAUNCH_FILES = ("driver.launch", "mission.launch", "orchestration.launch", "pose_remap.launch", "rviz.launch",
                "sim.launch")


def _dump(env, launch, *args):
    r = subprocess.run(["roslaunch", "--dump-params", "snake_autonomy", launch, *args], env=env,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    return yaml.safe_load(r.stdout)


@pytest.mark.parametrize("name", LAUNCH_FILES)
def test_every_launch_arg_has_a_doc(root, name):
    undocumented = [a.get("name") for a in ET.parse(root / "launch" / name).getroot().findall("arg")
                    if not a.get("doc", "").strip()]
    assert not undocumented, f"{name}: args without doc: {undocumented}"


def test_sim_launch_defaults_in_a_clone(root):
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root))
    params = _dump(env, "sim.launch")
    assert params["/sim/port"] == str(root / ".ws" / "snake_sim_bus")
    assert params["/driver/port"] == params["/sim/port"]
    assert params["/mission/results_dir"] == str(root / "results")
    assert params["/use_sim_time"] is False
    assert "camera_color_optical_frame" in params["/robot_description"]


def test_sim_launch_defaults_outside_a_clone_use_ros_home(root, tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "SNAKE_AUTONOMY_ROOT"}
    env["ROS_HOME"] = str(tmp_path)
    params = _dump(env, "sim.launch", "use_sim_time:=true")
    assert params["/sim/port"] == str(tmp_path / "snake_sim_bus")
    assert params["/mission/results_dir"] == str(tmp_path / "snake_autonomy_results")
    assert params["/use_sim_time"] is True


def test_driver_launch_mock_port_follows_the_clone_and_hardware_port_stays(root):
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root))
    assert _dump(env, "driver.launch", "mock:=true")["/driver/port"] == str(root / ".ws" / "snake_bus")
    assert _dump(env, "driver.launch")["/driver/port"] == "/dev/ttyUSB0"
    assert _dump(env, "mission.launch", "results_dir:=/data/runs")["/mission/results_dir"] == "/data/runs"


def test_sim_launch_lists_no_required_arg(root):
    """`roslaunch --ros-args`: every arg a user may leave out has a default (roslaunch calls an arg with
    an empty default "Required")."""
    r = subprocess.run(["roslaunch", "--ros-args", "snake_autonomy", "sim.launch"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "Required" not in r.stdout, r.stdout
    for arg in ("world", "classifier", "results_dir", "robot", "record"):
        assert f"\n  {arg} (default " in r.stdout, arg


def test_sim_launch_robot_reaches_every_node_and_a_world_is_recorded(root):
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root))
    params = _dump(env, "sim.launch", "robot:=chang_rectilinear", "world:=config/worlds/one_obstacle.yaml")
    robot_yaml = str(root / "config" / "robots" / "chang_rectilinear.yaml")
    assert params["/sim/robot_config"].endswith("/config/robots/chang_rectilinear.yaml")
    assert params["/planner/robot_config"] == params["/sim/robot_config"]
    assert os.path.samefile(params["/sim/robot_config"], robot_yaml)
    assert params["/driver/robot"] == "chang_rectilinear"
    assert '<robot name="chang_rectilinear">' in params["/robot_description"]
    assert params["/planner/nav_config"].endswith("/config/nav_chang_rectilinear.yaml")
    assert params["/nav_record/robot"] == "chang_rectilinear"
    assert params["/nav_record/results_dir"] == str(root / "results")
    assert params["/nav_record/world"] == params["/planner/world"] == str(root / "config/worlds/one_obstacle.yaml")
    assert "/mission/mission" not in params
    # without a world: the mission, no planner and no nav recorder; the default robot is COBRA
    params = _dump(env, "sim.launch")
    assert "/nav_record/robot" not in params and "/planner/world" not in params and "/sim/world" not in params
    assert params["/mission/robot"] == "cobra" and params["/driver/robot"] == "cobra"
