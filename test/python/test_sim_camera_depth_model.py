"""The depth sim_node publishes with a world: its ~depth_model (sim.depth_noise.named_depth_model)
applied in the head camera's render process (sim.camera_process.CameraProcess). d435i gives the
seeded noise and holes of config/sim.yaml depth_noise:, perfect the exact render."""
import numpy as np
import pytest

from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.depth_noise import named_depth_model


@pytest.fixture(scope="module")
def scene(root):
    """A plant in the one-obstacle world and its nav camera (what sim_node builds with a world)."""
    from snake_autonomy import _core
    from snake_autonomy.planning.rectilinear.config import NavConfig
    from snake_autonomy.sim.plant import Plant
    from snake_autonomy.sim.scene import world_plant_fields
    from snake_autonomy.sim.world_file import load_world
    cfg = NavConfig.from_yaml()
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    fields = world_plant_fields(load_world(root / "config" / "worlds" / "one_obstacle.yaml"), 0.8)
    sim_cfg = SimConfig.from_yaml(str(root / "config" / "sim.yaml"))
    params = sim_cfg.draw(seed=0, num_joints=robot.num_joints)
    plant = Plant(robot, params, fields["start_base"], scene_xml=fields["scene_xml"], assets_xml=fields["assets_xml"])
    plant.step_to(0.2)
    return plant, cfg, params


def _depth(scene, name: str) -> np.ndarray:
    from snake_autonomy.sim.camera_process import CameraProcess
    plant, cfg, params = scene
    model = named_depth_model(name, params.config.depth_noise, cfg.intrinsics.fx, params.rng("depth_noise"))
    cam = CameraProcess(plant.mjcf, cfg.intrinsics, cfg.mount, colour=False, depth=True, depth_model=model)
    try:
        cam.request(plant.time_s, plant.data.qpos, plant.frame_transform("base_link"))
        for _ in range(600):
            frame = cam.poll(0.1)
            if frame is not None:
                return frame.depth_m
    finally:
        cam.close()
    raise AssertionError("no frame from the render process in 60 s")


def test_d435i_depth_has_the_seeded_noise_and_holes_and_perfect_is_exact(scene):
    plant, cfg, params = scene
    perfect, noisy = _depth(scene, "perfect"), _depth(scene, "d435i")
    noise_cfg = params.config.depth_noise
    # perfect: the render itself (the same seeded model applied to it gives the published d435i frame)
    again = named_depth_model("d435i", noise_cfg, cfg.intrinsics.fx, params.rng("depth_noise"))(perfect)
    np.testing.assert_array_equal(noisy, again)
    seen = perfect > 0
    assert seen.mean() > 0.3
    holes = seen & (noisy == 0)
    too_near = seen & (perfect < noise_cfg.min_range_m)
    assert too_near.any() and not noisy[too_near].any()          # below the D435i's minimum Z: no depth
    assert holes.sum() > too_near.sum()                          # and the obstacle's edges
    both = seen & (noisy > 0)
    err = noisy[both] - perfect[both]
    sigma = named_depth_model("d435i", noise_cfg, cfg.intrinsics.fx, params.rng("x")).sigma_m(perfect[both])
    assert np.count_nonzero(err) > 0.99 * both.sum()
    assert np.std(err / sigma) == pytest.approx(1.0, rel=0.1)   # the z^2 noise of depth_noise:


def test_an_unknown_depth_model_is_refused_by_name():
    with pytest.raises(ValueError, match=r"depth_model: expected one of d435i, perfect, got 'noisy'"):
        named_depth_model("noisy", SimConfig().depth_noise, 615.0, np.random.default_rng(0))
