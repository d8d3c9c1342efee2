"""The head camera rendered in a child process (sim/camera_process.py, what sim_node uses with a
world): the same frame as HeadCamera in-process, one request at a time."""
import numpy as np
import pytest


def test_child_render_matches_the_in_process_camera(root):
    from snake_autonomy import _core
    from snake_autonomy.planning.rectilinear.config import NavConfig
    from snake_autonomy.sim.camera import HeadCamera
    from snake_autonomy.sim.camera_process import CameraProcess
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.sim.plant import Plant
    from snake_autonomy.sim.scene import world_plant_fields
    from snake_autonomy.sim.world_file import load_world
    cfg = NavConfig.from_yaml()
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    fields = world_plant_fields(load_world(root / "config" / "worlds" / "one_obstacle.yaml"), 0.8)
    params = SimConfig.from_yaml(str(root / "config" / "sim.yaml")).draw(seed=0, num_joints=robot.num_joints)
    plant = Plant(robot, params, fields["start_base"], scene_xml=fields["scene_xml"], assets_xml=fields["assets_xml"])
    plant.step_to(0.2)
    T_wb = plant.frame_transform("base_link")
    cam = CameraProcess(plant.mjcf, cfg.intrinsics, cfg.mount, colour=True, depth=True)
    try:
        assert cam.idle and cam.request(0.2, plant.data.qpos, T_wb)
        assert not cam.request(0.2, plant.data.qpos, T_wb)      # busy: one at a time
        frame = None
        for _ in range(600):
            frame = cam.poll(0.1)
            if frame is not None:
                break
        assert frame is not None and cam.idle and cam.stats["frames"] == 1
    finally:
        cam.close()
    local = HeadCamera(plant.model, cfg.intrinsics, cfg.mount)
    try:
        ref = local.render(plant.data, T_wb, 0.2, colour=False, depth=True, labels=False)
    finally:
        local.close()
    assert frame.T_world_camera == pytest.approx(ref.T_world_camera)
    assert frame.rgb.shape == (480, 640, 3) and frame.depth_m.shape == (480, 640)
    seen = (frame.depth_m > 0) & (ref.depth_m > 0)
    assert seen.mean() > 0.3
    assert np.median(np.abs(frame.depth_m[seen] - ref.depth_m[seen])) < 1e-3
