"""The gyro's calibration at rest (estimation/rest_calibration.py) and the fusion's first state built on
it (estimation/vio_fusion.py): the mean rate of a still window is the bias prior's mean; a window that
moved or is too short is not calibrated (zero mean, the wide std) and the fusion says so, naming what
it measured. The IMU samples are stubs: a known offset plus the BMI055's white noise."""
import logging
import math

import numpy as np
import pytest

from snake_autonomy.estimation.rest_calibration import RestSettings, calibrate_gyro_at_rest
from snake_autonomy.estimation.vio_fusion import FusionParams, VioFusion, load_fusion_params

RATE_HZ, NOISE_RAD_S = 200.0, 2.4e-3          # the BMI055's white noise per sample at 200 Hz
OFFSET = np.radians([0.6, -0.9, 0.4])         # a zero-rate offset within the datasheet's +-1 deg/s
GRAVITY = np.array([0.0, 0.0, 9.80665])
K = np.array([[307.5, 0.0, 160.0], [0.0, 307.5, 120.0], [0.0, 0.0, 1.0]])


def settings(window_s=2.0):
    p = FusionParams(rest_calibration_s=window_s)
    return RestSettings(p.rest_calibration_s, p.prior_gyro_bias_sigma_rad_s, p.uncalibrated_gyro_bias_sigma_rad_s,
                        p.rest_gyro_std_rad_s, p.rest_gyro_rate_rad_s, p.rest_accel_m_s2)


def imu_samples(seconds, seed=0, turning_rad_s=0.0):
    """(t, gyro, accel) at 200 Hz ending at t = 0: the offset and noise, plus a 1 Hz turn of this amplitude."""
    rng = np.random.default_rng(seed)
    t = np.arange(-int(seconds * RATE_HZ), 1) / RATE_HZ
    gyro = OFFSET + NOISE_RAD_S * rng.standard_normal((len(t), 3))
    gyro[:, 2] += turning_rad_s * np.sin(2 * math.pi * t)
    accel = GRAVITY + 0.015 * rng.standard_normal((len(t), 3))
    return t, gyro, accel


def test_a_still_window_gives_the_offset_within_its_noise():
    for seed in range(5):
        t, gyro, accel = imu_samples(2.0, seed)
        cal = calibrate_gyro_at_rest(gyro, accel, -t[0], settings())
        standard_error = NOISE_RAD_S / math.sqrt(len(t))
        assert cal.calibrated and cal.detail.startswith("calibrated at rest: gyro mean")
        assert np.all(np.abs(cal.bias_rad_s - OFFSET) < 4 * standard_error), cal.bias_rad_s - OFFSET
        assert cal.sigma_rad_s == pytest.approx(max(1e-4, standard_error), rel=0.15)


def test_a_window_that_moved_or_is_too_short_is_not_calibrated_and_says_what_it_measured():
    t, gyro, accel = imu_samples(2.0, turning_rad_s=0.1)       # a slow turn: 0.07 rad/s std about z
    cal = calibrate_gyro_at_rest(gyro, accel, -t[0], settings())
    assert not cal.calibrated and np.array_equal(cal.bias_rad_s, np.zeros(3)) and cal.sigma_rad_s == 5e-3
    assert "moved during the rest window (gyro std 0.07" in cal.detail and "> 0.01 rad/s" in cal.detail
    t, gyro, accel = imu_samples(2.0)
    cal = calibrate_gyro_at_rest(gyro, accel + np.array([0.0, 4.0, 0.0]), -t[0], settings())   # pushed sideways
    assert not cal.calibrated and "specific force 10.590 m/s^2 off gravity by more than 0.3" in cal.detail
    t, gyro, accel = imu_samples(0.5)
    cal = calibrate_gyro_at_rest(gyro, accel, -t[0], settings())
    assert not cal.calibrated and "span 0.50 s (101 samples), less than the 2 s window" in cal.detail
    cal = calibrate_gyro_at_rest(gyro, accel, -t[0], settings(window_s=0.0))    # calibrated beforehand
    assert not cal.calibrated and np.array_equal(cal.bias_rad_s, np.zeros(3)) and cal.sigma_rad_s == 1e-4


def first_frame(seconds, turning_rad_s=0.0, params=None):
    """A fusion's first frame (stamp 0, a blank image) after these IMU samples."""
    vio = VioFusion(K, np.eye(4), params=params)
    for t, g, a in zip(*imu_samples(seconds, turning_rad_s=turning_rad_s)):
        vio.add_imu(t, g, a)
    vio.add_frame(np.zeros((240, 320, 3), np.uint8), np.zeros((240, 320), np.float32), 0.0)
    return vio


def test_the_fusions_first_state_takes_the_calibrated_bias_and_records_why_not_when_the_robot_moved(caplog):
    with caplog.at_level(logging.WARNING):
        vio = first_frame(3.0)                   # 3 s of samples: the last 2 s are the window
    assert vio.calibration.calibrated
    np.testing.assert_allclose(vio._bias.gyroscope(), OFFSET, atol=4 * NOISE_RAD_S / math.sqrt(400))
    assert vio.calibration.detail.endswith("over 3.00 s (401 samples)")
    with caplog.at_level(logging.WARNING):
        moved = first_frame(2.0, turning_rad_s=0.5)
    assert not moved.calibration.calibrated and np.allclose(moved._bias.gyroscope(), 0.0, atol=1e-9)
    assert "robot moved during the rest window (gyro std 0.35" in moved.calibration.detail
    assert not caplog.records                    # recorded only: vio_node and the batch summary report it once


def test_the_rest_settings_are_validated_by_name(tmp_path):
    path = tmp_path / "estimation.yaml"
    for text, message in {"fusion: {rest_calibration_s: -1}": "fusion.rest_calibration_s: must be a finite number "
                                                              ">= 0, got -1.0",
                          "fusion: {rest_gyro_std_rad_s: 0}": "fusion.rest_gyro_std_rad_s: must be a finite number "
                                                              "> 0, got 0.0",
                          "fusion: {uncalibrated_gyro_bias_sigma_rad_s: .nan}":
                              "fusion.uncalibrated_gyro_bias_sigma_rad_s: must be a finite number > 0, "
                              "got nan"}.items():
        path.write_text(text)
        with pytest.raises(ValueError) as exc:
            load_fusion_params(path)
        assert message in str(exc.value)
    path.write_text("fusion: {rest_calibration_s: 0}")
    assert load_fusion_params(path).rest_calibration_s == 0.0
