"""The D435i-like depth model (sim/depth_noise.py) and how depth traversability treats its invalid
pixels (perception/depth_traversability.py): noise growing with z^2, no depth below the minimum
range, beyond the range and at edges, seeded per run, the open floor still ground."""
import numpy as np
import pytest

from snake_autonomy.paths import config_path
from snake_autonomy.perception.camera_model import LABEL_GROUND, CameraIntrinsics
from snake_autonomy.perception.depth_traversability import DepthTraversability, fill_unknown_below_ground
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.depth_noise import DepthNoise, DepthNoiseConfig, depth_sigma_m, edge_mask

FX = 615.0


def model(seed: int = 0, **kw) -> DepthNoise:
    return DepthNoise(DepthNoiseConfig(**kw), FX, np.random.default_rng(seed))


@pytest.mark.parametrize("z_m", [1.0, 2.0])
def test_noise_std_on_a_flat_wall_follows_the_z_squared_formula(z_m):
    wall = np.full((480, 640), z_m, np.float32)
    noisy = model()(wall)
    valid = noisy > 0
    assert valid.mean() > 0.99                       # a flat wall has no edges
    expected = z_m ** 2 * 0.08 / (FX * 0.05)         # Intel's RMS formula: 2.6 mm at 1 m, 10.4 mm at 2 m
    assert depth_sigma_m(z_m, FX, 0.05, 0.08) == pytest.approx(expected)
    std = float(np.std(noisy[valid] - z_m))
    assert std == pytest.approx(expected, rel=0.2), (std, expected)
    assert abs(float(np.mean(noisy[valid] - z_m))) < 0.1 * expected


def test_no_depth_below_the_minimum_range_or_beyond_the_maximum():
    ramp = np.tile(np.linspace(0.05, 0.3, 640, dtype=np.float32), (480, 1))   # 0.4 mm per column: no edge
    noisy = model(min_range_m=0.105)(ramp)
    assert not noisy[ramp < 0.1].any()
    assert (noisy[ramp > 0.11] > 0).mean() > 0.99
    far = model(max_range_m=4.0)(np.full((40, 40), 4.5, np.float32))
    assert not far.any()


def test_depth_edges_lose_a_band_of_pixels_on_both_sides():
    step = np.full((100, 100), 1.5, np.float32)
    step[:, :50] = 0.5                                # a box's side 0.5 m away, the wall behind at 1.5 m
    noisy = model(edge_band_px=2)(step)
    assert not noisy[:, 48:52].any()                  # 2 px each side of the discontinuity
    assert noisy[:, :47].all() and noisy[:, 53:].all()
    # a smooth floor-like ramp is not an edge
    assert not edge_mask(np.tile(np.linspace(0.3, 0.6, 100), (100, 1)).T, 0.1, 2).any()


def test_the_noise_is_seeded_per_run():
    wall = np.full((50, 50), 1.0, np.float32)
    assert np.array_equal(model(seed=3)(wall), model(seed=3)(wall))
    assert not np.array_equal(model(seed=3)(wall), model(seed=4)(wall))


def test_bad_depth_noise_values_are_refused_naming_the_key():
    with pytest.raises(ValueError, match=r"depth_noise\.subpixel: must be a finite number > 0, got 0"):
        SimConfig.from_dict({"depth_noise": {"subpixel": 0}})
    with pytest.raises(ValueError, match=r"depth_noise\.min_range_m: must be below max_range_m"):
        SimConfig.from_dict({"depth_noise": {"min_range_m": 5.0, "max_range_m": 4.0}})
    with pytest.raises(ValueError, match=r"depth_noise\.edge_band_px: expected int, got 1\.5"):
        SimConfig.from_dict({"depth_noise": {"edge_band_px": 1.5}})
    with pytest.raises(ValueError, match=r"depth_noise\.bogus: unknown key"):
        SimConfig.from_dict({"depth_noise": {"bogus": 1}})


def test_unknown_cells_join_the_region_only_below_ground():
    # one column per case, rows top (0) to bottom: G ground, U unknown, O obstacle (measured, not ground)
    cases = {"UUGUU": [0, 0, 1, 1, 1],     # the near band under the floor: ground
             "OUUUU": [0, 0, 0, 0, 0],     # unknown under an obstacle: not ground
             "UUUUU": [0, 0, 0, 0, 0],     # nothing measured: not ground
             "GOUGU": [1, 0, 0, 1, 1]}     # a hole in the floor joins it; the obstacle's shadow does not
    ground = np.array([[c == "G" for c in k] for k in cases]).T
    unknown = np.array([[c == "U" for c in k] for k in cases]).T
    assert fill_unknown_below_ground(ground, unknown).T.astype(int).tolist() == list(cases.values())


@pytest.fixture(scope="module")
def open_floor(root):
    """COBRA's nav camera on an open carpet floor: the perfect render and its T_ground_camera."""
    from snake_autonomy import _core
    from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera
    from snake_autonomy.sim.camera import HeadCamera
    from snake_autonomy.sim.plant import Plant
    from snake_autonomy.sim.scene import build_scene
    from snake_autonomy.sim.world_file import World
    cfg = NavConfig.from_yaml()
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    params = SimConfig.from_yaml(str(root / "config" / "sim.yaml")).draw(seed=0)
    w = World.from_dict({"start": [0, 0, 0], "goal": [3, 0], "goal_radius_m": 0.3, "floor_texture": "carpet"})
    scene = build_scene(w)
    plant = Plant(robot, params, w.start_rad, scene_xml=scene.scene_xml, assets_xml=scene.assets_xml)
    cam = HeadCamera(plant.model, cfg.intrinsics, cfg.mount)
    frame = cam.render(plant.data, plant.frame_transform("base_link"), colour=False)
    cam.close()
    return frame, cfg, T_ground_camera(cfg.mount, robot.link_radius_m)


def test_a_noisy_render_of_an_open_floor_is_still_ground_near_the_robot(open_floor):
    frame, cfg, T_gc = open_floor
    noise_cfg = SimConfig.from_yaml(config_path("sim.yaml")).depth_noise      # the nav runs' model
    noisy = DepthNoise(noise_cfg, cfg.intrinsics.fx, np.random.default_rng(0))(frame.depth_m)
    near_floor = (frame.labels == LABEL_GROUND) & (frame.depth_m > 0) & (frame.depth_m < 1.5)
    # the floor at the image's bottom is nearer than the sensor's minimum range: those rows have no depth
    too_near = near_floor & (frame.depth_m < noise_cfg.min_range_m)
    assert too_near.sum() > 0.1 * near_floor.sum() and not noisy[too_near].any()
    ground = DepthTraversability(cfg.intrinsics, T_gc, cfg.depth, seed=0)(noisy)
    assert ground[near_floor].mean() > 0.9, ground[near_floor].mean()
    assert ground[too_near].mean() > 0.9          # unknown under measured floor counts with it
    perfect = DepthTraversability(cfg.intrinsics, T_gc, cfg.depth, seed=0)(frame.depth_m)
    assert perfect[near_floor].mean() > 0.9


def test_the_intrinsics_of_the_default_camera_give_the_documented_figures():
    k = CameraIntrinsics.d435i_like()
    assert depth_sigma_m(1.0, k.fx, 0.05, 0.08) == pytest.approx(0.0026, abs=1e-4)
    assert depth_sigma_m(2.0, k.fx, 0.05, 0.08) == pytest.approx(0.0104, abs=1e-4)
