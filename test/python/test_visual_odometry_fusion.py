"""Visual-inertial fusion (estimation/vio_fusion.py): the visual odometry on the simulator's renders
(test_visual_odometry.py's straight crawl: 1 cm a frame at 10 Hz, i.e. 0.1 m/s) with IMU samples of
sim/imu.py's BMI055-like error model on the true readings of that motion (no rotation, constant
velocity: the specific force is gravity's reaction), at 200 Hz; and a physically simulated crawl:
the plant driven by the rectilinear gait in the textured test room, its head IMU (ImuSensor.poll)
and the camera rendered at the IMU's camera_link.
"""
import math

import numpy as np
import pytest

from snake_autonomy.estimation.pose_remap import load_camera_calibration
from snake_autonomy.estimation.visual_odometry import VisualOdometry, load_vo_params
from snake_autonomy.estimation.vio_fusion import (FusionParams, VioFusion, level_pose, load_fusion_params,
                                                  local_to_ros, ros_to_local)
from snake_autonomy.estimation.visual_odometry import LOST, LOST_COVARIANCE, OK
from snake_autonomy.perception.camera_model import R_LINK_OPTICAL
from snake_autonomy.sim.imu import DEG, MICRO_G_M_S2, ImuConfig, ImuSensor
from snake_autonomy.transforms import make_transform, rpy_to_matrix

from test_visual_odometry import K, render_path, textured_room

FRAME_S = 0.1
T_IMU_CAMERA = make_transform(R_LINK_OPTICAL)      # the IMU at camera_link (sim/imu.py)


@pytest.fixture(scope="module")
def straight(root):
    return render_path(root, "straight")


class Run:
    """Feeds frames and the IMU samples before each to a VioFusion; the truth is the straight
    crawl's constant velocity, continued past the rendered frames. A constant velocity without
    rotation reads as rest to an IMU: the still detector is off unless params say otherwise."""

    def __init__(self, frames, params=None, camera_matrix=None, vo_params=None):
        self.frames = frames
        self.T_world_imu0 = frames[0].T_world_camera @ np.linalg.inv(T_IMU_CAMERA)
        self.velocity = (frames[1].T_world_camera[:3, 3] - frames[0].T_world_camera[:3, 3]) / FRAME_S
        self.f_body = self.T_world_imu0[:3, :3].T @ np.array([0.0, 0.0, 9.80665])
        self.imu = ImuSensor(ImuConfig(gyro_offset_deg_s=0.0), np.random.default_rng(1))
        params = params or FusionParams(still_gyro_rad_s=0.0)
        self.vio = VioFusion(K() if camera_matrix is None else camera_matrix, T_IMU_CAMERA, vo_params, params,
                             initial_imu_pose=self.T_world_imu0)
        self.n_imu = 0

    def frame(self, i, rgb, depth):
        t = FRAME_S * i
        while self.n_imu * 0.005 <= t + 1e-9:
            s = self.imu.measure(self.n_imu * 0.005, np.zeros(3), self.f_body)
            self.vio.add_imu(s.t_s, s.angular_velocity_rad_s, s.linear_acceleration_m_s2)
            self.n_imu += 1
        return self.vio.add_frame(rgb, depth, t)

    def error_m(self, result, i):
        truth = self.frames[0].T_world_camera[:3, 3] + self.velocity * FRAME_S * i
        return float(np.linalg.norm(result.T_world_camera[:3, 3] - truth))


def test_fused_crawl_then_two_seconds_blank_dead_reckons_with_growing_covariance(straight):
    run = Run(straight)
    for i, f in enumerate(straight):
        r = run.frame(i, f.rgb, f.depth_m)
        assert r.state == OK, r.reason
        assert run.error_m(r, i) < 0.005                        # measured: at most 2.8 mm
        # the motion between frames is measured: the covariance grows as odometry's drift does
        assert np.all(np.diag(r.covariance) < 1e-3) and np.array_equal(r.covariance, r.marginal_covariance)
    seen = r
    black, no_depth = np.zeros_like(straight[0].rgb), np.zeros_like(straight[0].depth_m)
    traces = [np.trace(seen.marginal_covariance[:3, :3])]
    n = len(straight)
    for i in range(n, n + 20):                                  # 2 s of blank frames
        r = run.frame(i, black, no_depth)
        assert r.state == LOST and r.reason.startswith("visual odometry lost")
        assert np.array_equal(r.covariance, np.eye(6) * LOST_COVARIANCE)
        traces.append(np.trace(r.marginal_covariance[:3, :3]))
    assert all(b > a for a, b in zip(traces, traces[1:])), traces
    # dead-reckoned, not held: it moved on about as far as the truth (0.2 m); the error (measured
    # 2.6 cm) within 3 marginal stds
    moved = np.linalg.norm(r.T_world_camera[:3, 3] - seen.T_world_camera[:3, 3])
    assert 0.1 < moved < 0.3, moved
    err = run.error_m(r, n + 19)
    assert err < 0.1 and err < 3.0 * math.sqrt(traces[-1]), (err, math.sqrt(traces[-1]))


def test_the_imu_gate_refuses_a_visual_jump(straight):
    """After half a second of tracking the IMU knows the 0.1 m/s; a frame 7 cm further on is refused
    (gate_m 3 cm). The next motion is measured from the refused frame (its pose may be in the
    odometry's keyframe): the frame back on the true path is refused too, and tracking resumes on
    the one after it, consistent with the IMU's motion."""
    run = Run(straight, FusionParams(gate_m=0.03, vo_reset_after_lost=5, still_gyro_rad_s=0.0))
    for i in range(5):
        assert run.frame(i, straight[i].rgb, straight[i].depth_m).ok
    r = run.frame(5, straight[12].rgb, straight[12].depth_m)
    assert r.state == LOST and r.reason.startswith("IMU gate") and "allowed" in r.reason, r.reason
    assert r.vo.ok                                              # the visual odometry itself tracked it
    assert np.array_equal(r.covariance, np.eye(6) * LOST_COVARIANCE)
    assert run.error_m(r, 5) < 0.01                             # the IMU's prediction, not the jump
    r = run.frame(6, straight[6].rgb, straight[6].depth_m)
    assert r.state == LOST and r.reason.startswith("IMU gate"), r.reason
    r = run.frame(7, straight[7].rgb, straight[7].depth_m)
    assert r.state == OK, r.reason
    assert run.error_m(r, 7) < 0.01


def test_covariance_frames_round_trip_and_levelling():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((6, 6))
    cov = A @ A.T
    R = rpy_to_matrix(0.3, -0.2, 1.1)
    assert np.allclose(local_to_ros(ros_to_local(cov, R), R), cov)
    # a level IMU rolled and pitched: levelling on its specific force finds the roll and pitch
    R_world_imu = rpy_to_matrix(math.radians(10), math.radians(-20), 0.0)
    T = level_pose(R_world_imu.T @ np.array([0.0, 0.0, 9.81]))
    assert np.allclose(T[:3, :3] @ (R_world_imu.T @ [0, 0, 1.0]), [0, 0, 1.0])
    assert np.allclose(T[:3, :3], R_world_imu, atol=1e-9)      # zero yaw, as given


def test_config_matches_the_simulated_imu_and_errors_name_the_field(root, tmp_path):
    params = load_fusion_params(root / "config" / "estimation.yaml")
    assert params == FusionParams()
    imu = ImuConfig()
    assert params.gyro_noise_density_rad_s_per_sqrt_hz == pytest.approx(
        imu.gyro_noise_density_deg_s_per_sqrt_hz * DEG, rel=1e-3)
    assert params.accel_noise_density_m_s2_per_sqrt_hz == pytest.approx(       # 10 x: aliased contact spikes
        10.0 * imu.accel_noise_density_ug_per_sqrt_hz * MICRO_G_M_S2, rel=1e-3)
    assert params.gyro_bias_walk_rad_s_per_sqrt_s == imu.gyro_bias_walk_rad_s_per_sqrt_s
    assert params.accel_bias_walk_m_s2_per_sqrt_s == imu.accel_bias_walk_m_s2_per_sqrt_s
    path = tmp_path / "estimation.yaml"
    for text, message in {"fusion: {lag_s: 0}": "fusion.lag_s: must be a finite number > 0, got 0.0",
                          "fusion: {vo_reset_after_lost: -1}": "fusion.vo_reset_after_lost: must be an integer >= 0, "
                                                               "got -1",
                          "fusion: {vo_factor: absolute}": "fusion.vo_factor: unknown key (value 'absolute')",
                          "fusion: {gate: 1}": "fusion.gate: unknown key (value 1)",
                          "fusion: {vo_from_keyframe: 1}": "fusion.vo_from_keyframe: must be true or false, "
                                                           "got 1"}.items():
        path.write_text(text)
        with pytest.raises(ValueError) as exc:
            load_fusion_params(path)
        assert str(exc.value) == f"{path}: {message}"


def test_the_removed_options_are_refused_as_unknown(tmp_path):
    """Options measured and not kept were removed with their code: the keyframe points' depth noise
    in the PnP covariance (vo.depth_sigma_1m_m) and a robust loss on the visual between factors
    (fusion.vo_robust_loss, vo_robust_k). A config still naming one is refused, the key named."""
    path = tmp_path / "estimation.yaml"
    for load, section, key, value in ((load_vo_params, "vo", "depth_sigma_1m_m", "0.0052"),
                                      (load_fusion_params, "fusion", "vo_robust_loss", "huber"),
                                      (load_fusion_params, "fusion", "vo_robust_k", "1.345")):
        path.write_text(f"{section}: {{{key}: {value}}}")
        with pytest.raises(ValueError) as exc:
            load(path)
        assert f"{section}.{key}: unknown key" in str(exc.value), str(exc.value)


def drive_plant(root, gait_name, duration_s, scene=None, start_frames_s=0.0, blank=(), params=None):
    """The plant driven by a gait from rest for duration_s, its head IMU polled every physics step
    into a VioFusion (params) from start_frames_s on, frames at 10 Hz (320x240, D435i-like depth
    noise) from the head's camera_link (config/camera.yaml: the IMU's frame) in scene (the test
    room's by default); frames whose time falls in blank=(t0, t1) are black with no depth. Returns
    a list of (t, fused result, visual odometry alone, the camera's true pose)."""
    from snake_autonomy import _core
    from snake_autonomy.perception.camera_model import CameraIntrinsics, CameraMount
    from snake_autonomy.sim.camera import HeadCamera
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.sim.cpg_gait import CpgGait
    from snake_autonomy.sim.depth_noise import DepthNoise, DepthNoiseConfig
    from snake_autonomy.sim.plant import Plant
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    library = _core.GaitLibrary.from_yaml(str(root / "config" / "gaits.yaml"))
    config = SimConfig.from_yaml(str(root / "config" / "sim.yaml"))
    camera_in_head = load_camera_calibration(root / "config" / "camera.yaml").camera_in_head
    scene_xml, assets_xml = scene or textured_room()
    plant = Plant(robot, config.draw(seed=0), (0.0, 0.0, 0.0), scene_xml=scene_xml, assets_xml=assets_xml,
                  imu_in_head=camera_in_head)
    imu = ImuSensor(config.imu, np.random.default_rng(2), step_s=plant.dt_s)
    focal = K()[0, 0]
    intrinsics = CameraIntrinsics(320, 240, focal, focal, 160.0, 120.0)
    noise = DepthNoise(DepthNoiseConfig(), focal, np.random.default_rng(0))
    cam = HeadCamera(plant.model, intrinsics, CameraMount((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), depth_model=noise)
    gait = CpgGait(robot, library, gait_name)

    def imu_pose():
        return plant.frame_transform("head_link") @ camera_in_head
    vio = vo = None
    out, frame = [], int(round(start_frames_s / FRAME_S))
    for step in range(1, int(round(duration_s / plant.dt_s)) + 1):
        t = step * plant.dt_s
        plant.set_joint_targets(gait.joint_angles(robot, t))
        plant.step_to(t)
        sample = imu.poll(plant)
        if vio is None and t + 1e-9 >= start_frames_s:
            vio = VioFusion(K(), T_IMU_CAMERA, params=params, initial_imu_pose=imu_pose())
            vo = VisualOdometry(K(), initial_pose=imu_pose() @ T_IMU_CAMERA)
        if sample is not None and vio is not None:
            vio.add_imu(sample.t_s, sample.angular_velocity_rad_s, sample.linear_acceleration_m_s2)
        if vio is not None and t + 1e-9 >= frame * FRAME_S:
            f = cam.render(plant.data, imu_pose(), labels=False)       # mount: identity, at camera_link
            rgb, depth = f.rgb, f.depth_m
            if blank and blank[0] <= t < blank[1]:
                rgb, depth = np.zeros_like(rgb), np.zeros_like(depth)
            out.append((t, vio.add_frame(rgb, depth, t), vo.process(rgb, depth, t), f.T_world_camera))
            frame += 1
    cam.close()
    return out


def test_fused_rectilinear_crawl_of_the_simulated_robot(root):
    """3 s of the rectilinear gait from rest: frames at 10 Hz from the head's camera_link, the IMU
    polled every physics step. The head's path is 19 cm (4.9 cm net: the gait sways it), turning up
    to 12 deg. Neither the odometry nor the fusion loses track; both stay within 2 cm of the truth
    (measured: the odometry 9.8 mm, the fusion 13.7 mm)."""
    run = drive_plant(root, "rectilinear", 3.0)
    fused_err, vo_err, path = [], [], 0.0
    for i, (t, r, rv, T) in enumerate(run):
        assert r.ok and rv.ok, (t, r.reason, rv.reason)
        fused_err.append(np.linalg.norm(r.T_world_camera[:3, 3] - T[:3, 3]))
        vo_err.append(np.linalg.norm(rv.T_odom_camera[:3, 3] - T[:3, 3]))
        path += np.linalg.norm(T[:3, 3] - run[i - 1][3][:3, 3]) if i else 0.0
    assert len(run) == 31 and path > 0.15
    assert max(fused_err) < 0.02 and max(vo_err) < 0.02, (max(fused_err), max(vo_err))


def test_sidewinding_blank_interval_comes_back_to_the_truth(root):
    """Sidewinding in the odometry room (sim.launch feedback:=vo's, here centred 0.67 m from the
    camera's start) from 4 s into the gait, 1.5 s of blank frames at 5.5 s: the motion between
    tracked frames and the motion priors bound the estimate, and once the
    odometry tracks again it stays near the truth. Measured in the room lit without shadows: 19 of
    41 frames lost (16 blank, one refused by the IMU gate), 6.8 cm off when the frames go blank
    (the tracked frames before drift 6 cm in 0.7 s), 22.8 cm at the blank's end (the IMU alone for
    1.5 s), 2.3-4.1 cm once tracking is back, 4.1 cm at the end. With the overhead shadow-casting
    light the room had before: 0.8 cm when they go blank, 12.6 cm at the blank's end, 1.1 cm at the
    end."""
    from snake_autonomy.sim.scene import vo_room
    room = vo_room()
    run = drive_plant(root, "sidewind", 8.0, scene=(room.scene_xml, room.assets_xml), start_frames_s=4.0,
                      blank=(5.5, 7.0))
    err = [float(np.linalg.norm(r.T_world_camera[:3, 3] - T[:3, 3])) for _, r, _, T in run]
    assert all(not r.ok for t, r, _, _ in run if 5.5 <= t < 7.0)
    assert max(err) < 0.3, max(err)                                  # bounded while blind
    after = [r.ok for t, r, _, _ in run if t >= 7.05]
    assert sum(after) >= 0.8 * len(after), after
    assert err[-1] < 0.08, err[-1]


def test_motion_priors_hold_a_still_robot_in_the_dark():
    """10 s at rest with every frame blank, the first pose 3 deg off in roll and an accelerometer
    bias the fusion does not know (0.05 m/s^2 along x and z): the IMU alone runs away (measured:
    7.6 m); the velocity prior (0.5 m/s) and the height prior (5 cm) hold it within 2 cm; with the
    IMU at rest taken as standing still (velocity zero within 1 cm/s) within 1 mm."""
    blank_rgb, blank_depth = np.zeros((240, 320, 3), np.uint8), np.zeros((240, 320), np.float32)
    T0 = np.eye(4)
    T0[:3, :3] = rpy_to_matrix(math.radians(3.0), 0.0, 0.0)
    finals = {}
    for name, params in (("default", FusionParams()), ("priors", FusionParams(still_gyro_rad_s=0.0)),
                         ("none", FusionParams(velocity_prior_sigma_m_s=0.0, height_prior_sigma_m=0.0,
                                               still_gyro_rad_s=0.0))):
        imu = ImuSensor(ImuConfig(gyro_offset_deg_s=0.0), np.random.default_rng(1))
        vio = VioFusion(K(), T_IMU_CAMERA, params=params, initial_imu_pose=T0)
        n_imu = 0
        for i in range(101):
            t = FRAME_S * i
            while n_imu * 0.005 <= t + 1e-9:
                s = imu.measure(n_imu * 0.005, np.zeros(3), np.array([0.05, 0.0, 9.80665 + 0.05]))
                vio.add_imu(s.t_s, s.angular_velocity_rad_s, s.linear_acceleration_m_s2)
                n_imu += 1
            r = vio.add_frame(blank_rgb, blank_depth, t)
            assert not r.ok
        finals[name] = float(np.linalg.norm(r.T_world_imu[:3, 3]))
    assert finals["none"] > 2.0 and finals["priors"] < 0.05 and finals["default"] < 0.005, finals


def test_the_gate_takes_the_camera_after_refusing_it_gate_max_refused_times(straight):
    """A state that ran away refuses every visual pose, and the motion the camera measures could
    never bring it back (seen through ROS: 1.9 m/s dead-reckoned, 31 frames refused in 6.6 s). With
    a gate that refuses everything, gate_max_refused 3 takes the fourth tracked frame; 0 never."""
    for max_refused, expected in ((3, [False, False, False, True, False]), (0, [False] * 5)):
        run = Run(straight, FusionParams(gate_max_refused=max_refused, vo_reset_after_lost=0, still_gyro_rad_s=0.0))
        for i in range(5):
            assert run.frame(i, straight[i].rgb, straight[i].depth_m).ok
        run.vio._gate = lambda *args: "IMU gate: refused (test)"
        states = [run.frame(i, straight[i].rgb, straight[i].depth_m).ok for i in range(5, 10)]
        assert states == expected, (max_refused, states)


def test_motions_are_measured_from_the_keyframes_state(straight):
    """With vo_from_keyframe a tracked frame's motion is measured from the frame its keyframe was
    taken at (the crawl keeps its first keyframe for several frames); without it, from the previous
    frame. Either way the measured motion is within 5 mm of the truth's, its covariance positive
    definite, and the crawl fuses within 1 cm."""
    spans = {}
    for from_keyframe in (True, False):
        run = Run(straight, FusionParams(still_gyro_rad_s=0.0, vo_from_keyframe=from_keyframe))
        spans[from_keyframe] = []
        for i in range(8):
            r = run.frame(i, straight[i].rgb, straight[i].depth_m)
            assert r.ok or i == 0, r.reason
            assert run.error_m(r, i) < 0.01
            if i == 0:
                assert r.measured_motion is None                # nothing to measure from yet
                continue
            since, T_rel, cov = r.measured_motion
            frames = int(round((r.stamp - since) / FRAME_S))
            truth = run.T_world_imu0[:3, :3].T @ run.velocity * FRAME_S * frames     # in the IMU's frame
            assert np.linalg.norm(T_rel[:3, 3] - truth) < 0.005, (i, T_rel[:3, 3], truth)
            assert np.linalg.eigvalsh(cov).min() > 0.0
            spans[from_keyframe].append(frames)
    assert max(spans[True]) > 1, spans
    assert set(spans[False]) == {1}, spans
