"""The frame's own depth in the visual odometry's PnP fit (estimation/visual_odometry.py,
depth_inverse_sigma_per_m): synthetic keyframe points and their pixels and depths in the current
frame, no rendering. On the simulated star mission the worst visual motions rested on one near
matched point that was a mismatch: the 2D fit absorbs it, the depth at its pixel gives it away.
"""
from dataclasses import replace

import cv2
import numpy as np

from snake_autonomy.estimation.visual_odometry import VisualOdometry, VoParams, _Keyframe

FOCAL_PX = 615.0 * 320 / 640           # the odometry camera: the D435i-like 640x480, halved
K = np.array([[FOCAL_PX, 0, 160.0], [0, FOCAL_PX, 120.0], [0, 0, 1]])
DEPTH_NOISE = 0.0052                   # the simulator's depth std over z^2 (sim/depth_noise.py)


def _scene(rng, n, near_m, far_m, u=(20, 300), v=(20, 220)):
    """n keyframe points (keyframe camera frame) between near_m and far_m, within the pixels u, v."""
    uv = np.column_stack([rng.uniform(*u, n), rng.uniform(*v, n)])
    z = rng.uniform(near_m, far_m, n)
    return np.column_stack([(uv[:, 0] - K[0, 2]) * z / FOCAL_PX, (uv[:, 1] - K[1, 2]) * z / FOCAL_PX, z])


def _project(points_cam):
    return points_cam[:, :2] / points_cam[:, 2:] * FOCAL_PX + K[:2, 2]


def _position(rvec, tvec):
    """The camera's position in the keyframe from OpenCV's pose of the keyframe in the camera."""
    return -cv2.Rodrigues(rvec)[0].T @ np.ravel(tvec)


def _odometry(depth_in_fit: bool) -> VisualOdometry:
    params = VoParams()
    return VisualOdometry(K, params if depth_in_fit else replace(params, depth_inverse_sigma_per_m=0.0))


def test_a_near_mismatch_whose_depth_disagrees_is_left_out_of_the_fit():
    # 30 exact matches at 1.5-3.5 m and one near mismatch (0.3 m): its pixel 1.5 px off its point's
    # projection, within the 2D inlier threshold, and its depth another surface's (0.45 m)
    rng = np.random.default_rng(1)
    points = np.vstack([_scene(rng, 30, 1.5, 3.5), [[-0.05, 0.04, 0.3]]])
    t_true = np.array([-0.01, 0.0, -0.02])            # the keyframe's points in the camera: points + t
    in_camera = points + t_true
    pixels = _project(in_camera)
    pixels[-1, 0] += 1.5
    depth = in_camera[:, 2].copy()
    depth[-1] = 0.45
    near = len(points) - 1

    rvec, tvec, inliers = _odometry(False)._solve_pnp(points, pixels, depth)
    assert near in inliers                             # the 2D fit takes it ...
    assert np.linalg.norm(_position(rvec, tvec) + t_true) > 1e-3     # ... and moves by over 1 mm

    rvec, tvec, inliers = _odometry(True)._solve_pnp(points, pixels, depth)
    assert near not in inliers
    assert len(inliers) == near                         # every other match kept
    assert np.linalg.norm(_position(rvec, tvec) + t_true) < 1e-5


def test_the_depth_steadies_a_fit_on_a_far_patch():
    # 25 points in a 60 px patch 2.5-3.5 m away (a textured wall across the room), 1 px noise and
    # the simulator's depth noise: the 2D fit's translation is weak, the depth holds it better, and
    # the covariance says so
    errors = {False: [], True: []}
    sigmas = {False: [], True: []}
    t_true = np.array([0.02, 0.0, -0.05])
    for seed in range(20):
        rng = np.random.default_rng(seed)
        u, v = rng.uniform(60, 260), rng.uniform(60, 180)
        points = _scene(rng, 25, 2.5, 3.5, (u - 30, u + 30), (v - 22, v + 22))
        in_camera = points + t_true
        pixels = _project(in_camera) + rng.normal(0.0, 1.0, (len(points), 2))
        depth = in_camera[:, 2] + rng.normal(0.0, 1.0, len(points)) * DEPTH_NOISE * in_camera[:, 2] ** 2
        keyframe = _Keyframe(np.eye(4), np.zeros((6, 6)), points, np.zeros((len(points), 32), np.uint8), 0.0)
        for with_depth in (False, True):
            vo = _odometry(with_depth)
            rvec, tvec, inliers = vo._solve_pnp(points, pixels, depth)
            errors[with_depth].append(np.linalg.norm(_position(rvec, tvec) + t_true))
            T = np.eye(4)
            T[:3, :3] = cv2.Rodrigues(rvec)[0].T
            T[:3, 3] = _position(rvec, tvec)
            cov, _ = vo._covariance_of(T, keyframe, points[inliers], pixels[inliers], rvec, tvec, depth[inliers])
            sigmas[with_depth].append(np.sqrt(np.trace(cov[:3, :3])))
    rms = {k: np.sqrt(np.mean(np.square(v))) for k, v in errors.items()}
    assert rms[True] < 0.8 * rms[False]                # measured: 3.5 against 5.3 cm
    assert np.median(sigmas[True]) < np.median(sigmas[False])
