"""The head camera (sim/camera.py, perception/camera_model.py): depth, segmentation, intrinsics."""
import numpy as np
import pytest

from snake_autonomy.perception.camera_model import LABEL_GROUND, LABEL_OBSTACLE, CameraIntrinsics, CameraMount
from snake_autonomy.sim.camera import HeadCamera
from snake_autonomy.sim.world_file import World


@pytest.fixture(scope="module")
def box_frame(root):
    from snake_autonomy import _core
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.sim.plant import Plant
    from snake_autonomy.sim.scene import build_scene
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    params = SimConfig.from_yaml(str(root / "config" / "sim.yaml")).draw(seed=0)
    w = World.from_dict({"start": [0, 0, 0], "goal": [3, 0], "goal_radius_m": 0.3, "floor_texture": "carpet",
                         "obstacles": [{"type": "box", "x": 1.0, "y": 0.0, "size_m": [0.2, 0.6, 0.3]}]})
    scene = build_scene(w)
    plant = Plant(robot, params, w.start_rad, scene_xml=scene.scene_xml, assets_xml=scene.assets_xml)
    cam = HeadCamera(plant.model, CameraIntrinsics.d435i_like(), CameraMount((0.05, 0.0, 0.0), (0.0, 15.0, 0.0)))
    frame = cam.render(plant.data, plant.frame_transform("base_link"))
    cam.close()
    return frame


def test_intrinsics_and_camera_info():
    k = CameraIntrinsics.d435i_like()
    info = k.camera_info()
    assert info["K"] == [615.0, 0.0, 320.0, 0.0, 615.0, 240.0, 0.0, 0.0, 1.0]
    assert len(info["P"]) == 12 and info["width"] == 640 and info["height"] == 480
    uv = k.project(np.array([[0.1, -0.05, 1.0]]))
    assert uv[0] == pytest.approx([320 + 61.5, 240 - 30.75])
    with pytest.raises(ValueError, match="camera.intrinsics.fx: must be a number > 0, got -1"):
        CameraIntrinsics.from_dict({"width": 640, "height": 480, "fx": -1, "fy": 615, "cx": 320, "cy": 240})


def test_box_depth_matches_geometry(box_frame):
    f = box_frame
    obstacle = f.labels == LABEL_OBSTACLE
    assert obstacle.sum() > 10000
    # every obstacle pixel's ray meets the box's front face x = 0.9 m (world) where it shows it
    pts = f.intrinsics.back_project(f.depth_m)[obstacle]            # optical frame
    world = pts @ f.T_world_camera[:3, :3].T + f.T_world_camera[:3, 3]
    front = np.abs(world[:, 0] - 0.9) < 0.01
    assert front.mean() > 0.95                                       # the rest: the box's top
    assert np.abs(world[front, 1]).max() < 0.3 + 0.01
    # the floor's points lie on z = 0 within 5 mm (the visual floor is 0.2 mm up)
    ground = f.intrinsics.back_project(f.depth_m)[f.labels == LABEL_GROUND]
    gz = ground @ f.T_world_camera[:3, :3].T[:, 2] + f.T_world_camera[2, 3]
    assert np.percentile(np.abs(gz), 99) < 0.005


def test_segmentation_separates_floor_and_obstacle(box_frame):
    f = box_frame
    # bottom centre: floor; the image centre column just above the floor/box edge: the box
    assert f.labels[470, 320] == LABEL_GROUND
    col = f.labels[:, 320]
    top_of_floor = np.nonzero(col != LABEL_GROUND)[0].max()
    assert col[top_of_floor] == LABEL_OBSTACLE
    # the box's bottom edge is where geometry puts it: the ray to (0.9, 0, 0)
    p_cam = np.linalg.inv(f.T_world_camera) @ np.array([0.9, 0.0, 0.0, 1.0])
    v_expected = f.intrinsics.project(p_cam[None, :3])[0, 1]
    assert abs(top_of_floor - v_expected) <= 2.0
