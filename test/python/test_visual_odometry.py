"""Visual odometry (estimation/visual_odometry.py) on head-camera frames rendered by the simulator.

The frames are MuJoCo renders (sim/camera.HeadCamera, colour + depth with the D435i-like depth
noise of sim/depth_noise.py) at 320x240 of a small textured room made for this test: four walls and
six boxes at 0.5-2 m, each with a coarse random texture (ORB needs corners; the nav worlds' floor
textures alias at the head's grazing view and give few repeatable features). The camera is moved
along prescribed poses (the robot's physics is not stepped): the poses are the ground truth.
Rendered once per session (about 0.2 s a frame).
"""
import math

import numpy as np
import pytest

from snake_autonomy.estimation.visual_odometry import (LOST, LOST_COVARIANCE, OK, VisualOdometry, VoParams,
                                                       load_vo_params, rotation_angle_deg)

WIDTH, HEIGHT = 320, 240
FOCAL_PX = 615.0 * WIDTH / 640           # the D435i-like 640x480 camera, halved
STEP_M = 0.01                            # the straight crawl: 1 cm per frame (10 cm/s at 10 Hz)
STEP_DEG = 1.5                           # the yaw turn: 1.5 deg per frame (15 deg/s at 10 Hz)
N_FRAMES = 20
# bounds on the estimated motion against ground truth, every frame (measured, worst frame: straight
# 3.3 mm and 0.84 deg, yaw 5.3 mm and 0.22 deg)
MAX_POSITION_ERROR_M = 0.01
MAX_ANGLE_ERROR_DEG = 1.0

_WALLS = [((2.0, 0.0), (0.02, 2.0)), ((-1.0, 0.0), (0.02, 2.0)), ((0.5, 1.5), (1.5, 0.02)),
          ((0.5, -1.5), (1.5, 0.02))]
_BOXES = [(0.7, 0.35, 0.12), (0.9, -0.3, 0.15), (1.2, 0.05, 0.1), (0.55, -0.15, 0.06), (1.4, 0.6, 0.2),
          (1.1, -0.7, 0.2)]
_COLOURS = [("0.8 0.7 0.3", "0.2 0.1 0.4"), ("0.3 0.6 0.8", "0.6 0.1 0.1"), ("0.7 0.4 0.6", "0.1 0.3 0.1"),
            ("0.6 0.8 0.5", "0.3 0.2 0.5"), ("0.9 0.9 0.2", "0.1 0.1 0.6"), ("0.2 0.8 0.8", "0.5 0.1 0.1"),
            ("0.9 0.5 0.2", "0.1 0.4 0.1"), ("0.8 0.8 0.8", "0.1 0.1 0.1"), ("0.5 0.9 0.3", "0.4 0.1 0.5"),
            ("0.9 0.6 0.7", "0.1 0.2 0.3")]


def textured_room():
    """(scene_xml, assets_xml) of the test room: a floor, four walls and six boxes, each with a
    random-dot texture (texels of 1-5 cm)."""
    assets, scene = [], ['<light name="room_light" dir="0.3 0.2 -1" directional="true" diffuse="0.7 0.7 0.7" '
                         'castshadow="false"/>']

    def material(name, texels, colours):
        rgb, mark = colours
        assets.append(f'<texture name="{name}_tex" type="2d" builtin="flat" mark="random" random="0.5" '
                      f'rgb1="{rgb}" rgb2="{rgb}" markrgb="{mark}" width="{texels}" height="{texels}"/>')
        assets.append(f'<material name="{name}_mat" texture="{name}_tex" texrepeat="1 1"/>')
    material("floor", 256, ("0.55 0.5 0.45", "0.25 0.2 0.2"))
    scene.append('<geom name="floor_visual" type="plane" pos="0 0 0.0002" size="3 3 0.1" material="floor_mat" '
                 'contype="0" conaffinity="0"/>')
    for k, ((x, y), (sx, sy)) in enumerate(_WALLS):
        material(f"wall{k}", 128, _COLOURS[k])
        scene.append(f'<geom name="obstacle_{k}" type="box" pos="{x} {y} 0.3" size="{sx} {sy} 0.3" '
                     f'material="wall{k}_mat" contype="2" conaffinity="1"/>')
    for j, (x, y, half) in enumerate(_BOXES):
        material(f"box{j}", 32, _COLOURS[4 + j])
        scene.append(f'<geom name="obstacle_{4 + j}" type="box" pos="{x} {y} {half}" size="{half} {half} {half}" '
                     f'euler="0 0 {30 * j}" material="box{j}_mat" contype="2" conaffinity="1"/>')
    return "\n".join(scene), "\n".join(assets)


def render_path(root, motion: str, n_frames: int = N_FRAMES, width: int = WIDTH, height: int = HEIGHT):
    """Frames (sim CameraFrame: rgb, depth_m, T_world_camera) of the head camera moving through the
    test room: motion "straight" (forward STEP_M a frame) or "yaw" (STEP_DEG a frame about the
    base's z axis), from the plant's start pose; D435i-like depth noise (seed 0)."""
    from snake_autonomy import _core
    from snake_autonomy.perception.camera_model import CameraIntrinsics, CameraMount
    from snake_autonomy.sim.camera import HeadCamera
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.sim.depth_noise import DepthNoise, DepthNoiseConfig
    from snake_autonomy.sim.plant import Plant
    from snake_autonomy.transforms import make_transform, rot_z
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    params = SimConfig.from_yaml(str(root / "config" / "sim.yaml")).draw(seed=0)
    scene_xml, assets_xml = textured_room()
    plant = Plant(robot, params, (0.0, 0.0, 0.0), scene_xml=scene_xml, assets_xml=assets_xml)
    focal = 615.0 * width / 640
    intrinsics = CameraIntrinsics(width, height, focal, focal, width / 2, height / 2)
    noise = DepthNoise(DepthNoiseConfig(), focal, np.random.default_rng(0))
    cam = HeadCamera(plant.model, intrinsics, CameraMount((0.05, 0.0, 0.0), (0.0, 5.0, 0.0)), depth_model=noise)
    start = plant.frame_transform("base_link")
    frames = []
    for i in range(n_frames):
        if motion == "straight":
            T = start.copy()
            T[:3, 3] += start[:3, 0] * STEP_M * i
        else:
            T = start @ make_transform(rot_z(math.radians(STEP_DEG * i)))
        frames.append(cam.render(plant.data, T, t_s=0.1 * i, labels=False))
    cam.close()
    return frames


@pytest.fixture(scope="session")
def straight(root):
    return render_path(root, "straight")


@pytest.fixture(scope="session")
def yaw(root):
    return render_path(root, "yaw")


def K():
    return np.array([[FOCAL_PX, 0.0, WIDTH / 2], [0.0, FOCAL_PX, HEIGHT / 2], [0.0, 0.0, 1.0]])


def errors(result, frame, first):
    """(position error m, angle error deg) of the estimate against the truth relative to `first`."""
    truth = np.linalg.inv(first.T_world_camera) @ frame.T_world_camera
    est = result.T_odom_camera
    return (float(np.linalg.norm(est[:3, 3] - truth[:3, 3])),
            rotation_angle_deg(truth[:3, :3].T @ est[:3, :3]))


@pytest.mark.parametrize("motion", ["straight", "yaw"])
def test_estimated_motion_matches_ground_truth(motion, request):
    frames = request.getfixturevalue(motion)
    vo = VisualOdometry(K())
    worst_m, worst_deg = 0.0, 0.0
    for f in frames:
        r = vo.process(f.rgb, f.depth_m, f.t_s)
        assert r.state == OK, r.reason
        assert r.inliers >= vo.params.min_inliers
        e_m, e_deg = errors(r, f, frames[0])
        worst_m, worst_deg = max(worst_m, e_m), max(worst_deg, e_deg)
    truth = np.linalg.inv(frames[0].T_world_camera) @ frames[-1].T_world_camera
    moved_m, turned_deg = np.linalg.norm(truth[:3, 3]), rotation_angle_deg(truth[:3, :3])
    assert (moved_m > 0.15) if motion == "straight" else (turned_deg > 25.0)
    assert worst_m < MAX_POSITION_ERROR_M and worst_deg < MAX_ANGLE_ERROR_DEG, (worst_m, worst_deg)


def test_covariance_is_positive_and_grows_with_keyframes(yaw):
    vo = VisualOdometry(K())
    results = [vo.process(f.rgb, f.depth_m, f.t_s) for f in yaw]
    assert np.all(results[0].covariance == 0.0) and results[0].keyframe      # the odometry frame's origin
    assert vo.keyframes >= 2                                                 # 28.5 deg: the view changes
    for r in results[1:]:
        assert np.allclose(r.covariance, r.covariance.T)
        assert np.linalg.eigvalsh(r.covariance).min() > 0.0
        assert np.all(np.diag(r.covariance) < 1e-3)                         # < 3 cm, < 1.8 deg std
    after_switch = next(i for i, r in enumerate(results) if i > 0 and r.keyframe)
    assert np.trace(results[-1].covariance) > np.trace(results[after_switch - 1].covariance)


def test_blank_frames_lose_tracking_hold_the_pose_and_recover(straight):
    vo = VisualOdometry(K())
    for f in straight[:5]:
        held = vo.process(f.rgb, f.depth_m, f.t_s)
        assert held.ok
    black = np.zeros_like(straight[0].rgb)
    no_depth = np.zeros_like(straight[0].depth_m)
    for i in range(3):
        r = vo.process(black, no_depth, 0.5 + 0.1 * i)
        assert r.state == LOST and "too few features" in r.reason
        assert np.array_equal(r.covariance, np.eye(6) * LOST_COVARIANCE)
        assert np.array_equal(r.T_odom_camera, held.T_odom_camera)
    for f in straight[8:12]:                       # the camera moved on meanwhile: 3 frames unseen
        r = vo.process(f.rgb, f.depth_m, f.t_s)
        assert r.state == OK, r.reason
        e_m, e_deg = errors(r, f, straight[0])
        assert e_m < MAX_POSITION_ERROR_M and e_deg < MAX_ANGLE_ERROR_DEG


def test_depth_holes_give_no_3d_points(straight):
    first = straight[0]
    holes = first.depth_m.copy()
    holes[:, : WIDTH // 2] = np.nan                # the left half: NaN, the top rows: 0
    holes[: HEIGHT // 4, :] = 0.0
    vo = VisualOdometry(K())
    r = vo.process(first.rgb, holes, 0.0)
    assert r.ok and r.keyframe
    pts = vo._keyframe.points
    assert np.all(np.isfinite(pts)) and np.all(pts[:, 2] >= vo.params.min_depth_m)
    u = pts[:, 0] / pts[:, 2] * FOCAL_PX + WIDTH / 2
    v = pts[:, 1] / pts[:, 2] * FOCAL_PX + HEIGHT / 2
    assert u.min() >= WIDTH // 2 - 0.5 and v.min() >= HEIGHT // 4 - 0.5
    # tracking goes on against the keyframe's remaining points
    for f in straight[1:6]:
        r = vo.process(f.rgb, f.depth_m, f.t_s)
        assert r.ok, r.reason
        assert errors(r, f, first)[0] < MAX_POSITION_ERROR_M
    # a mask: features only where it is set
    mask = np.zeros(first.depth_m.shape, bool)
    mask[:, WIDTH // 3:] = True
    masked = VisualOdometry(K())
    assert masked.process(first.rgb, first.depth_m, 0.0, mask=mask).ok
    pts = masked._keyframe.points
    assert (pts[:, 0] / pts[:, 2] * FOCAL_PX + WIDTH / 2).min() >= WIDTH // 3 - 0.5
    with pytest.raises(ValueError, match="mask: shape"):
        masked.process(first.rgb, first.depth_m, 0.1, mask=mask[:10])
    # no depth at all: no keyframe, lost
    vo = VisualOdometry(K())
    r = vo.process(first.rgb, np.full_like(first.depth_m, np.nan), 0.0)
    assert r.state == LOST and "no keyframe yet: 0 features with depth" in r.reason
    assert np.all(np.diag(r.covariance) == LOST_COVARIANCE)


def test_a_gross_step_is_refused(straight, yaw):
    """A frame that PnP places far from the last good pose (here: a view 28.5 deg round with a
    max_step_deg of 10) is lost, not a jump in the odometry."""
    vo = VisualOdometry(K(), VoParams(max_step_deg=10.0))
    assert vo.process(yaw[0].rgb, yaw[0].depth_m, 0.0).ok
    r = vo.process(yaw[-1].rgb, yaw[-1].depth_m, 0.1)
    assert r.state == LOST, r
    assert r.reason.startswith("pose jumped") and "max_step_deg 10" in r.reason
    # the same pair with the default 45 deg: tracked
    vo = VisualOdometry(K())
    vo.process(yaw[0].rgb, yaw[0].depth_m, 0.0)
    assert vo.process(yaw[-1].rgb, yaw[-1].depth_m, 0.1).ok
    assert np.array_equal(r.T_odom_camera, np.eye(4))


def test_config_file_and_its_errors(root, tmp_path):
    assert load_vo_params(root / "config" / "estimation.yaml") == VoParams()
    cases = {"vo: {n_features: abc}": "vo.n_features: must be an integer in [50, 20000], got 'abc'",
             "vo: {ransac_reprojection_px: -1}": "vo.ransac_reprojection_px: must be a finite number in "
                                                 "[0.1, 50], got -1.0",
             "vo: {min_depth_m: 5}": "vo.min_depth_m: must be below max_depth_m (4), got 5.0",
             "vo: {keyframe_min_inliers: 10}": "vo.keyframe_min_inliers: must be at least min_inliers (20), got 10",
             "vo: {ratio: 0.7}": "vo.ratio: unknown key (value 0.7)",
             "vo: [1, 2]": "vo: expected a mapping, got [1, 2]",
             "vo: {max_step_m: .nan}": "vo.max_step_m: must be a finite number in [0.001, 100], got nan"}
    for text, message in cases.items():
        path = tmp_path / "estimation.yaml"
        path.write_text(text)
        with pytest.raises(ValueError) as exc:
            load_vo_params(path)
        assert str(exc.value) == f"{path}: {message}"
    with pytest.raises(ValueError, match="K: expected a 3x3 camera matrix"):
        VisualOdometry(np.eye(2))
    with pytest.raises(ValueError, match="depth_m: shape"):
        VisualOdometry(K()).process(np.zeros((HEIGHT, WIDTH), np.uint8), np.zeros((10, 10)), 0.0)


def test_a_lost_keyframe_view_falls_back_to_the_last_tracked_frame(straight):
    """Keyframes never switched by inliers or overlap (keyframe_min_inliers = min_inliers, overlap 0):
    when the keyframe's view is gone the last tracked frame becomes the keyframe, so tracking goes on
    (frame 19 alone against frame 0 finds too few matches)."""
    vo = VisualOdometry(K(), VoParams(keyframe_min_inliers=20, keyframe_min_overlap=0.0))
    for f in straight:
        r = vo.process(f.rgb, f.depth_m, f.t_s)
        assert r.ok, r.reason
        e_m, e_deg = errors(r, f, straight[0])
        assert e_m < MAX_POSITION_ERROR_M and e_deg < MAX_ANGLE_ERROR_DEG
    assert vo.keyframes >= 2
    alone = VisualOdometry(K())
    alone.process(straight[0].rgb, straight[0].depth_m, 0.0)
    assert not alone.process(straight[-1].rgb, straight[-1].depth_m, 1.9).ok


def test_each_pose_names_the_keyframe_it_was_measured_against(straight):
    """A tracked frame reports its keyframe's stamp and camera pose (a fusion measures the motion from
    there); after the fallback the last tracked frame is that keyframe, at its own stamp and pose."""
    vo = VisualOdometry(K(), VoParams(keyframe_min_inliers=20, keyframe_min_overlap=0.0))
    results = [vo.process(f.rgb, f.depth_m, f.t_s) for f in straight]
    assert results[0].keyframe_stamp is None                    # the first keyframe: measured against none
    by_stamp = {r.stamp: r for r in results}
    for r in results[1:]:
        assert r.ok, r.reason
        keyframe = by_stamp[r.keyframe_stamp]
        assert keyframe.stamp < r.stamp
        assert np.allclose(r.T_odom_keyframe, keyframe.T_odom_camera)
    assert len({r.keyframe_stamp for r in results[1:]}) >= 2    # the fallback switched the keyframe


def test_a_view_that_comes_back_is_placed_against_its_earlier_keyframe(yaw):
    """The camera turns 28.5 deg and back: with keyframe_memory the turn back is measured against the
    keyframes taken on the way out (the last frame, the first view again, against the first
    keyframe), so fewer keyframes are taken and no new error is added; without it, new keyframes."""
    there_and_back = list(yaw) + list(yaw[::-1])
    taken, last = {}, {}
    for memory in (0, 4):
        # keyframes switched early (below 150 inliers), so that the turn takes several
        vo = VisualOdometry(K(), VoParams(keyframe_memory=memory, keyframe_min_inliers=150))
        for i, f in enumerate(there_and_back):
            r = vo.process(f.rgb, f.depth_m, 0.1 * i)
            assert r.ok, r.reason
        taken[memory], last[memory] = vo.keyframes, r
    assert taken[4] < taken[0], taken
    assert last[4].keyframe_stamp == 0.0                        # the first keyframe, its view again
    e_m, e_deg = errors(last[4], yaw[0], yaw[0])
    assert e_m < MAX_POSITION_ERROR_M and e_deg < MAX_ANGLE_ERROR_DEG


def test_a_predicted_pose_guides_the_matching(yaw):
    """A keyframe point is matched only to features within guided_radius_px of its projection at the
    predicted pose: the view 28.5 deg round is tracked with the true pose predicted, and lost (too
    few matches) with a prediction 15 deg off, whose projections fall about 80 px away."""
    first, last = yaw[0], yaw[-1]
    truth = np.linalg.inv(first.T_world_camera) @ last.T_world_camera
    off = truth.copy()
    off[:3, :3] = off[:3, :3] @ _rotation_y_deg(15.0)
    for predicted, tracked in ((truth, True), (off, False), (None, True)):
        vo = VisualOdometry(K(), VoParams(guided_radius_px=30.0))
        vo.process(first.rgb, first.depth_m, 0.0)
        r = vo.process(last.rgb, last.depth_m, 0.1, predicted=predicted)
        assert r.ok == tracked, (predicted is None, r.reason)
        if not tracked:
            assert r.reason.startswith("too few matches to the keyframe"), r.reason


def _rotation_y_deg(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_features_are_detected_again_where_there_is_depth(straight):
    """ORB's strongest corners on a far wall beyond max_depth_m (here: the left three quarters, depth
    6 m, full contrast) took all 600 features and none had depth; detected again within the pixels
    with depth (the right quarter, a quarter of the contrast) the frame becomes the keyframe."""
    first = straight[0]
    rgb, depth = first.rgb.copy(), first.depth_m.copy()
    depth[:, : 3 * WIDTH // 4] = 6.0
    rgb[:, 3 * WIDTH // 4:] = rgb[:, 3 * WIDTH // 4:] // 4 + 96
    never = VisualOdometry(K(), VoParams(depth_redetect_below=0)).process(rgb, depth, 0.0)
    assert never.state == LOST and "no keyframe yet: 0 features with depth" in never.reason
    vo = VisualOdometry(K())
    r = vo.process(rgb, depth, 0.0)
    assert r.ok and r.keyframe and r.inliers >= 20, r.reason
    u = vo._keyframe.points[:, 0] / vo._keyframe.points[:, 2] * FOCAL_PX + WIDTH / 2
    assert u.min() >= 3 * WIDTH // 4 - 0.5
