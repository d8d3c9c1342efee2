"""The URDF generated from the robot YAML and config/camera.yaml (src/core/urdf.cpp, `snake_autonomy urdf`):
accepted by check_urdf, capsule collisions, inertia at each segment's centroid, one transmission per
joint, the camera's links from the calibration. Frame poses vs the core: test/cpp_ros (kdl_parser)."""
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from snake_autonomy import _core
from snake_autonomy.cli import main as cli_main


@pytest.fixture(scope="module")
def model(cobra_yaml):
    return _core.RobotModel.from_yaml(cobra_yaml)


@pytest.fixture(scope="module")
def urdf_text(root):
    r = subprocess.run([sys.executable, str(root / "scripts" / "snake_autonomy"), "urdf", "cobra"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return r.stdout


def _xyz(elem):
    return [float(v) for v in elem.find("origin").get("xyz").split()]


def test_check_urdf_accepts_it(urdf_text, tmp_path):
    if shutil.which("check_urdf") is None:
        pytest.fail("check_urdf is missing: scripts/bootstrap installs it (liburdfdom-tools)")
    path = tmp_path / "cobra.urdf"
    path.write_text(urdf_text)
    r = subprocess.run(["check_urdf", str(path)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "root Link: base_link" in r.stdout
    assert "camera_color_optical_frame" in r.stdout and "link_11" in r.stdout


def test_every_body_is_a_capsule_of_cylinder_and_two_spheres(urdf_text, model):
    robot = ET.fromstring(urdf_text)
    bodies = [link for link in robot.findall("link") if link.find("visual") is not None]
    assert len(bodies) == model.num_joints + 1          # base_link (head) and one rotor link per joint
    for link in bodies:
        shapes = [c.find("geometry")[0] for c in link.findall("collision")]
        assert sorted(s.tag for s in shapes) == ["cylinder", "sphere", "sphere"], link.get("name")
        assert all(float(s.get("radius")) == pytest.approx(model.link_radius_m) for s in shapes)
        sphere_x = sorted(_xyz(c)[0] for c in link.findall("collision") if c.find("geometry")[0].tag == "sphere")
        length = float(next(s for s in shapes if s.tag == "cylinder").get("length"))
        assert sphere_x[1] - sphere_x[0] == pytest.approx(length)   # one sphere at each end of the cylinder


def test_inertia_sits_at_each_segments_centroid_and_masses_add_up(urdf_text, model):
    robot = ET.fromstring(urdf_text)
    inertial = {link.get("name"): link.find("inertial") for link in robot.findall("link")
                if link.find("inertial") is not None}
    total = sum(float(i.find("mass").get("value")) for i in inertial.values())
    assert total == pytest.approx(sum(model.masses_kg))
    for j in range(1, model.num_joints + 1):
        i = inertial[f"link_{j}_rotor"]
        assert _xyz(i) == pytest.approx([-model.link_length_m / 2, 0, 0])   # the rotor spans 0 .. -L
        assert float(i.find("mass").get("value")) == pytest.approx(model.masses_kg[j + 1])
        tensor = i.find("inertia")
        m, r, length = model.masses_kg[j + 1], model.link_radius_m, model.link_length_m
        assert float(tensor.get("ixx")) == pytest.approx(m * r * r / 2)
        assert float(tensor.get("iyy")) == pytest.approx(m * (3 * r * r + length * length) / 12)
    assert _xyz(inertial["head_link"]) == pytest.approx([model.head_length_m / 2, 0, 0])
    assert "base_link" not in inertial    # KDL: no inertia on the root link


def test_one_simple_transmission_per_joint_to_its_servo(urdf_text, model):
    robot = ET.fromstring(urdf_text)
    transmissions = robot.findall("transmission")
    assert [t.find("joint").get("name") for t in transmissions] == list(model.joint_names)
    for t, servo_id, direction in zip(transmissions, model.servo_ids, model.servo_directions):
        assert t.find("type").text == "transmission_interface/SimpleTransmission"
        assert t.find("actuator").get("name") == f"servo_{servo_id}"
        assert float(t.find("actuator/mechanicalReduction").text) == direction


def test_camera_links_follow_the_calibration(model):
    camera_in_head = np.eye(4)
    camera_in_head[:3, 3] = [0.03, -0.01, 0.02]
    c, s = np.cos(0.3), np.sin(0.3)
    camera_in_head[:3, :3] = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    robot = ET.fromstring(_core.make_urdf(model, camera_in_head=camera_in_head, camera_name="cam"))
    joints = {j.get("name"): j for j in robot.findall("joint")}
    mount = joints["cam_link_joint"]
    assert mount.find("parent").get("link") == "head_link" and mount.find("child").get("link") == "cam_link"
    assert _xyz(mount) == pytest.approx([0.03, -0.01, 0.02])
    roll, pitch, yaw = (float(v) for v in mount.find("origin").get("rpy").split())
    rx = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    ry = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]])
    rz = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    np.testing.assert_allclose(rz @ ry @ rx, camera_in_head[:3, :3], atol=1e-12)
    optical = joints["cam_color_optical_frame_joint"]
    assert optical.find("parent").get("link") == "cam_link"
    rpy = [float(v) for v in optical.find("origin").get("rpy").split()]
    assert rpy == pytest.approx([-np.pi / 2, 0, -np.pi / 2])   # REP 103: z forward, x right, y down


def test_cli_reads_the_camera_yaml_and_can_leave_it_out(capsys):
    assert cli_main(["urdf", "cobra", "--no-camera"]) == 0
    assert "camera_link" not in capsys.readouterr().out
    assert cli_main(["urdf", "cobra"]) == 0
    assert "camera_link" in capsys.readouterr().out
    assert cli_main(["urdf", "cobra", "--camera", "/nonexistent/camera.yaml"]) == 1
    assert "/nonexistent/camera.yaml" in capsys.readouterr().err
