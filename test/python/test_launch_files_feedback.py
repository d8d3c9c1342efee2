"""sim.launch's feedback values, resolved by roslaunch itself (--dump-params: nothing started): mocap
publishes base_pose from the simulator (no remapper, no vio_node), vio runs the pose remapper on the
simulated RTAB-Map's odom, vo runs vio_node (its camera topics, the odometry's frames, the estimation
config) and the pose remapper on vio_node's odom, all in the odom frame."""
import os
import xml.etree.ElementTree as ET

import pytest

from test_launch_files import _dump


@pytest.fixture(scope="module")
def dumps(root):
    env = dict(os.environ, SNAKE_AUTONOMY_ROOT=str(root))
    return {fb: _dump(env, "sim.launch", f"feedback:={fb}") for fb in ("mocap", "vio", "vo")}


def test_mocap_has_neither_remapper_nor_vio_node(dumps):
    p = dumps["mocap"]
    assert p["/sim/feedback"] == "mocap" and p["/sim/world_frame"] == "map"
    assert not any(k.startswith(("/pose_remapper/", "/vio/")) for k in p)


def test_vio_runs_the_remapper_on_the_simulated_odom(dumps):
    p = dumps["vio"]
    assert p["/sim/feedback"] == "vio" and p["/pose_remapper/world_frame"] == "odom"
    assert not any(k.startswith("/vio/") for k in p)


def test_vo_runs_vio_node_and_the_remapper_on_its_odom(root, dumps):
    p = dumps["vo"]
    assert p["/sim/feedback"] == "vo" and p["/sim/world_frame"] == "odom"
    assert p["/sim/vo_camera_rate_hz"] == 10
    assert p["/vio/odom_frame"] == "odom" == p["/pose_remapper/world_frame"]
    assert os.path.samefile(p["/vio/config"], root / "config" / "estimation.yaml")
    assert p["/mission/world_frame"] == "odom"


def test_vo_remaps_vio_nodes_camera_to_the_given_namespace(root):
    """vo_camera:= puts a relay between sim_node's camera and vio_node (test/ros/sim_vo.test does)."""
    node = next(n for n in ET.parse(root / "launch" / "sim.launch").getroot().iter("node")
                if n.get("type") == "vio_node")
    remaps = {r.get("from"): r.get("to") for r in node.findall("remap")}
    assert remaps == {f"camera/{k}": f"$(arg vo_camera)/{k}"
                      for k in ("color/image_raw", "color/camera_info", "depth/image_rect_raw")}
    assert node.get("if") == "$(eval arg('feedback') == 'vo')"
