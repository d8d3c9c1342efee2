"""Launch files: every arg documented; defaults that keep two clones apart (the pty of the simulated
bus and the results folder under the clone or $ROS_HOME, never a shared /tmp path); the URDF and
/use_sim_time parameters. Parameters are resolved by roslaunch itself (--dump-params: no master,
nothing started, but robot_description's command runs)."""
import json
import os
import subprocess
import xml.etree.ElementTree as ET

import pytest
import yaml

LAUNCH_FILES = ("bringup.launch", "driver.launch", "mission.launch", "navigation.launch", "orchestration.launch",
                "pose_remap.launch", "rviz.launch", "sim.launch", "sim_robot.launch")


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


@pytest.mark.parametrize("name", LAUNCH_FILES)
def test_no_launch_file_lists_a_required_arg(root, name):
    """`roslaunch --ros-args`: every arg a user may leave out has a default (roslaunch calls an arg whose
    default, or computed value, is empty "Required")."""
    r = subprocess.run(["roslaunch", "--ros-args", "snake_autonomy", name], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "Required" not in r.stdout, r.stdout
    if name == "sim.launch":
        for arg in ("world", "classifier", "results_dir", "robot", "record"):
            assert f"\n  {arg} (default " in r.stdout, arg


def test_the_defaults_that_mean_none_give_the_nodes_what_empty_gave(root):
    """none / config defaults (not empty, see above) reach the nodes as before: no mission (load via
    mission/load), no tracker overrides, the odometry's frame, config/driver.yaml's bus latency; and an
    empty value given on the command line still means the same."""
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root))
    for extra in ((), ("mission:=", "tracker_overrides:=", "results_dir:=")):
        mission = _dump(env, "mission.launch", *extra)
        assert (mission["/mission/mission"], mission["/mission/tracker_overrides"]) == ("", "")
        assert mission["/mission/results_dir"] == str(root / "results")
        assert os.path.samefile(mission["/mission/scout_config"], root / "config" / "scout.yaml")
    assert _dump(env, "mission.launch", "mission:=star")["/mission/mission"] == "star"
    assert _dump(env, "orchestration.launch")["/pose_remapper/world_frame"] == ""
    assert _dump(env, "pose_remap.launch", "world_frame:=map")["/pose_remapper/world_frame"] == "map"
    driver_yaml = yaml.safe_load((root / "config" / "driver.yaml").read_text())
    assert _dump(env, "driver.launch")["/driver/bus_latency_s"] == driver_yaml["bus_latency_s"]
    assert _dump(env, "driver.launch", "bus_latency_s:=")["/driver/bus_latency_s"] == driver_yaml["bus_latency_s"]
    assert _dump(env, "driver.launch", "mock:=true")["/driver/bus_latency_s"] == 0.05


RVIZ_SCRIPT = """
import json, sys
import roslaunch.config, roslaunch.xmlloader
cfg = roslaunch.config.load_config_default([(sys.argv[1], sys.argv[2:])], None, verbose=False,
    loader=roslaunch.xmlloader.XmlLoader(resolve_anon=False), assign_machines=False)
print(json.dumps({n.name: n.args for n in cfg.nodes}))
"""


def _node_args(root, launch, *args):
    """{node name: its args} of a launch file as roslaunch resolves it (nothing started)."""
    r = subprocess.run(["python3", "-c", RVIZ_SCRIPT, str(root / "launch" / launch), *args],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_rviz_launch_sets_a_fixed_frame_only_when_given(root):
    def rviz_args(*args):
        return _node_args(root, "rviz.launch", *args)["rviz"].split()

    assert rviz_args()[0] == "-d" and rviz_args()[1].endswith("/rviz/snake.rviz") and len(rviz_args()) == 2
    assert rviz_args("fixed_frame:=")[2:] == []
    assert rviz_args("fixed_frame:=map")[2:] == ["-f", "map"]


def test_a_navigation_run_with_rviz_has_the_navigation_config_and_the_path_travelled(root):
    """sim.launch world:=W rviz:=true (no mission node): rviz with rviz/nav.rviz in the world frame, and
    viz_node (the path travelled) started by rviz.launch."""
    nodes = _node_args(root, "sim.launch", "world:=one_obstacle", "rviz:=true")
    assert {"snake_viz", "planner", "nav_record"} <= set(nodes) and "mission" not in nodes
    assert nodes["rviz"].split()[1].endswith("/rviz/nav.rviz") and nodes["rviz"].split()[2:] == ["-f", "map"]


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
    assert "/mission/mission" not in params and params["/sim/mission"] == ""
    assert params["/planner/command_without_goal"] == "hold"     # navigation only: the heartbeat stays
    # without a world: the mission, no planner and no nav recorder; the default robot is COBRA
    params = _dump(env, "sim.launch")
    assert "/nav_record/robot" not in params and "/planner/world" not in params and "/sim/world" not in params
    assert params["/mission/robot"] == "cobra" and params["/driver/robot"] == "cobra"


RS_CAMERA_STUB = """<launch>
  <!-- a stand-in of realsense2_camera's rs_camera.launch: the args bringup.launch passes (as the real
       file declares them) and one node recording them -->
  <arg name="camera" default="camera"/>
  <arg name="align_depth" default="false"/>
  <arg name="enable_sync" default="false"/>
  <arg name="publish_tf" default="true"/>
  <node ns="$(arg camera)" pkg="realsense2_camera" type="stub" name="realsense2_camera">
    <param name="align_depth" value="$(arg align_depth)"/>
    <param name="publish_tf" value="$(arg publish_tf)"/>
  </node>
</launch>
"""
NODES_SCRIPT = """
import json, sys
import roslaunch.config, roslaunch.xmlloader
cfg = roslaunch.config.load_config_default([(sys.argv[1], sys.argv[2:])], None,
    loader=roslaunch.xmlloader.XmlLoader(resolve_anon=False), verbose=False, assign_machines=False)
print(json.dumps({(n.namespace.rstrip('/') + '/' + n.name): dict(n.remap_args) for n in cfg.nodes}))
"""


def _bringup_nodes(env, *args):
    r = subprocess.run(["python3", "-c", NODES_SCRIPT, os.path.join(env["SNAKE_LAUNCH_DIR"], "bringup.launch"),
                        *args], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_bringup_on_the_robot_parses_with_the_camera_driver_installed(root, tmp_path):
    """The real configuration (servos on /dev/ttyUSB0, the D435i, RTAB-Map's odometry, the remapper, the
    planner and its record), with realsense2_camera stood in by a package of the same name (it is not in
    Debian); rtabmap_ros's node needs no package to be parsed."""
    pkg = tmp_path / "realsense2_camera"
    (pkg / "launch").mkdir(parents=True)
    (pkg / "package.xml").write_text('<package format="2"><name>realsense2_camera</name><version>0.0.0</version>'
                                     '<description>stand-in</description><maintainer email="a@b.c">t</maintainer>'
                                     '<license>BSD</license></package>')
    (pkg / "launch" / "rs_camera.launch").write_text(RS_CAMERA_STUB)
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root), SNAKE_LAUNCH_DIR=str(root / "launch"),
               ROS_PACKAGE_PATH=f"{tmp_path}:{os.environ.get('ROS_PACKAGE_PATH', '')}")
    params = _dump(env, "bringup.launch")
    assert params["/driver/port"] == "/dev/ttyUSB0" and params["/driver/world_frame"] == "odom"
    assert params["/camera/realsense2_camera/align_depth"] is True
    assert params["/camera/realsense2_camera/publish_tf"] is False
    assert params["/rtabmap/rgbd_odometry/frame_id"] == "camera_link"
    assert params["/rtabmap/rgbd_odometry/publish_tf"] is False
    assert "/sim/port" not in params and "/planner/world" not in params
    nodes = _bringup_nodes(env)
    assert set(nodes) == {"/driver", "/robot_state_publisher", "/camera/realsense2_camera", "/rtabmap/rgbd_odometry",
                          "/pose_remapper", "/planner", "/nav_record"}
    assert nodes["/pose_remapper"]["odom"] == "/rtabmap/odom"
    assert nodes["/rtabmap/rgbd_odometry"]["depth/image"] == "/camera/aligned_depth_to_color/image_raw"
    assert nodes["/planner"]["camera/depth/image_rect_raw"] == "camera/aligned_depth_to_color/image_raw"
    # a mission instead of the planner; motion capture instead of RTAB-Map: no odometry, no remapper
    nodes = _bringup_nodes(env, "autonomy:=mission", "odometry:=mocap", "mission:=star")
    assert set(nodes) == {"/driver", "/robot_state_publisher", "/camera/realsense2_camera", "/mission", "/snake_viz"}


def test_bringup_without_the_camera_driver_names_it(root):
    r = subprocess.run(["roslaunch", "--nodes", "snake_autonomy", "bringup.launch"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode != 0 and "realsense2_camera" in r.stdout + r.stderr


def test_bringup_lists_no_required_arg_and_its_stand_ins_parse(root):
    r = subprocess.run(["roslaunch", "--ros-args", "snake_autonomy", "bringup.launch"], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0 and "Required" not in r.stdout, r.stdout + r.stderr
    world = str(root / "test" / "ros" / "worlds" / "nav_record.yaml")
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root), SNAKE_LAUNCH_DIR=str(root / "launch"))
    nodes = _bringup_nodes(env, "bus:=sim", "camera:=sim", "odometry:=sim", f"world:={world}")
    assert set(nodes) == {"/sim", "/driver", "/robot_state_publisher", "/pose_remapper", "/planner", "/nav_record"}
    assert nodes["/pose_remapper"]["odom"] == "odom"
    params = _dump(env, "bringup.launch", "bus:=sim", "camera:=sim", "odometry:=sim", f"world:={world}")
    assert params["/sim/feedback"] == "vio" and params["/sim/world"] == world
    assert params["/driver/port"] == params["/sim/port"] == str(root / ".ws" / "snake_sim_bus")
    assert params["/nav_record/pose_source"] == "vio" and params["/planner/world"] == world


def test_sim_launch_world_and_mission_run_both_the_planner_commanding_only_its_legs(root):
    """world:= and mission:= together: the mission node and planner_node; the planner takes goals only
    from the mission's navigate_to legs (no world goal) and is silent without one; the mission node
    records the run (no nav recorder)."""
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root))
    params = _dump(env, "sim.launch", "world:=config/worlds/one_obstacle.yaml", "mission:=tracker_planner_tracker")
    assert params["/mission/mission"] == params["/sim/mission"] == "tracker_planner_tracker"
    assert params["/planner/command_without_goal"] == "none"
    assert "/planner/world" not in params and "/nav_record/robot" not in params
    assert params["/sim/world"] == str(root / "config/worlds/one_obstacle.yaml")
    assert params["/mission/world_frame"] == params["/planner/world_frame"] == "map"
    # rviz:=true: one viz_node (mission.launch's; rviz.launch's too would be a second /snake_viz)
    r = subprocess.run(["python3", "-c", NODES_SCRIPT, str(root / "launch" / "sim.launch"), "rviz:=true",
                        "world:=config/worlds/one_obstacle.yaml", "mission:=tracker_planner_tracker"],
                       env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    nodes = set(json.loads(r.stdout.strip().splitlines()[-1]))
    assert {"/mission", "/planner", "/snake_viz", "/rviz"} <= nodes and "/nav_record" not in nodes, nodes


def test_bringup_both_runs_the_mission_node_and_a_silent_planner(root):
    world = str(root / "test" / "ros" / "worlds" / "nav_record.yaml")
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root), SNAKE_LAUNCH_DIR=str(root / "launch"))
    args = ("bus:=sim", "camera:=sim", "odometry:=sim", f"world:={world}", "autonomy:=both", "mission:=star")
    nodes = _bringup_nodes(env, *args)
    assert set(nodes) == {"/sim", "/driver", "/robot_state_publisher", "/pose_remapper", "/planner", "/mission",
                          "/snake_viz"}
    params = _dump(env, "bringup.launch", *args)
    assert params["/planner/command_without_goal"] == "none" and "/planner/world" not in params
    assert params["/mission/mission"] == "star" and params["/sim/world"] == world
    params = _dump(env, "bringup.launch", "bus:=sim", "camera:=sim", "odometry:=sim", f"world:={world}")
    assert params["/planner/command_without_goal"] == "hold" and params["/planner/world"] == world
