"""The PnP fit's covariance (estimation/visual_odometry.fit_covariance) on synthetic fits: keyframe
points seen from a known pose, their projections with pixel noise, the pose refined by OpenCV's
Levenberg-Marquardt from the truth; the Jacobians are OpenCV's (rvec, tvec), the covariance is in
those parameters. A calibrated covariance puts the fit's error within chi^2 6 dof 99 % (16.81)."""
import cv2
import numpy as np
import pytest

from snake_autonomy.estimation.visual_odometry import fit_covariance

FOCAL_PX = 307.5                       # the odometry camera's 320x240
K = np.array([[FOCAL_PX, 0.0, 160.0], [0.0, FOCAL_PX, 120.0], [0.0, 0.0, 1.0]])
RVEC = np.array([[0.01], [0.05], [0.0]])
TVEC = np.array([[0.03], [0.0], [0.02]])
CHI2_6_99 = 16.81


def points(rng, n_far, near_z_m=None):
    """n_far points 3-4 m away spread over the image, and one near point when near_z_m is given."""
    uv = np.column_stack([rng.uniform(20, 300, n_far), rng.uniform(20, 220, n_far)])
    z = rng.uniform(3.0, 4.0, n_far)
    if near_z_m is not None:
        uv, z = np.vstack([uv, [250.0, 180.0]]), np.r_[z, near_z_m]
    return np.column_stack([(uv[:, 0] - K[0, 2]) * z / FOCAL_PX, (uv[:, 1] - K[1, 2]) * z / FOCAL_PX, z])


def fit(obj, rng, noise_px, last_off_px=0.0):
    """(J (N, 2, 6), residuals (N, 2), the fit's error (rvec, tvec)) with the last point's
    observation moved by last_off_px (a mismatch)."""
    img = cv2.projectPoints(obj, RVEC, TVEC, K, None)[0].reshape(-1, 2) + rng.normal(0.0, noise_px, (len(obj), 2))
    img[-1, 0] += last_off_px
    _, rvec, tvec = cv2.solvePnP(obj, img, K, None, RVEC.copy(), TVEC.copy(), True, cv2.SOLVEPNP_ITERATIVE)
    proj, jac = cv2.projectPoints(obj, rvec, tvec, K, None)
    error = np.r_[(rvec - RVEC).ravel(), (tvec - TVEC).ravel()]
    return jac[:, :6].reshape(-1, 2, 6), proj.reshape(-1, 2) - img, error


def gauss_newton(J, r, pixel_sigma_px=1.0):
    n = len(J)
    scale = max(float(np.sum(r * r)) / pixel_sigma_px ** 2 / (2 * n - 6), 1.0)
    return scale * pixel_sigma_px ** 2 * np.linalg.inv(np.einsum("nai,naj->ij", J, J))


def nees(error, cov):
    return float(error @ np.linalg.solve(cov, error))


@pytest.mark.parametrize("seed", range(5))
def test_a_fit_resting_on_one_mismatched_near_point_gets_a_covariance_that_covers_its_error(seed):
    """60 points 3-4 m away fix the rotation, one 0.45 m away pins the translation; that one
    mismatched by 20 px is absorbed by the fit (its residual under 1 px, an inlier of any RANSAC)
    and puts the translation about 3 cm off. The Gauss-Newton covariance claims millimetres (its
    NEES in the hundreds: the star replay's bad frames); the fit's covariance covers the error."""
    rng = np.random.default_rng(seed)
    J, r, error = fit(points(rng, 60, near_z_m=0.45), rng, noise_px=0.5, last_off_px=20.0)
    assert np.linalg.norm(r[-1]) < 1.0 and np.linalg.norm(r, axis=1).max() < 2.0   # every point an inlier
    assert np.linalg.norm(error[3:]) > 0.02
    assert nees(error, gauss_newton(J, r)) > 100.0
    cov = fit_covariance(J, r, 1.0)
    assert nees(error, cov) < CHI2_6_99
    assert np.linalg.eigvalsh(cov - gauss_newton(J, r)).min() > -1e-12      # never below Gauss-Newton


@pytest.mark.parametrize("seed", range(5))
def test_a_clean_fit_keeps_the_gauss_newton_covariance(seed):
    """100 points spread over 1-4 m, 0.5 px noise, no mismatch: no inlier carries the fit, the
    covariance is Gauss-Newton's (within 2 times along every direction) and covers the error."""
    rng = np.random.default_rng(seed)
    obj = points(rng, 100)
    obj *= rng.uniform(0.3, 1.0, (len(obj), 1))                  # depths 0.9-4 m
    J, r, error = fit(obj, rng, noise_px=0.5)
    cov, gn = fit_covariance(J, r, 1.0), gauss_newton(J, r)
    whitened = np.linalg.inv(np.linalg.cholesky(gn))
    assert np.linalg.eigvalsh(whitened @ cov @ whitened.T).max() < 2.0
    assert nees(error, cov) < CHI2_6_99


def test_fewer_or_noisier_inliers_give_a_larger_covariance():
    """The same view: 20 inliers against 100, or 1.8 px of noise against 0.3 px: larger in every
    direction."""
    rng = np.random.default_rng(7)
    obj = points(rng, 100) * rng.uniform(0.3, 1.0, (100, 1))
    clean = fit_covariance(*fit(obj, rng, noise_px=0.3)[:2], 1.0)
    few = fit_covariance(*fit(obj[:20], rng, noise_px=0.3)[:2], 1.0)
    noisy = fit_covariance(*fit(obj, rng, noise_px=1.8)[:2], 1.0)
    for worse in (few, noisy):
        assert np.linalg.eigvalsh(worse - clean).min() > 0.0


def test_an_indeterminate_fit_is_lost():
    """Every point on one ray: the pose is not determined, the covariance is the lost one."""
    J = np.zeros((10, 2, 6))
    J[:, 0, 0] = 1.0
    assert np.all(np.diag(fit_covariance(J, np.zeros((10, 2)), 1.0)) >= 9999.0)
