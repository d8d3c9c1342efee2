"""estimation/motion_model.py: which IMU samples are at rest, and the crawling priors' pull on a state
(the whitened error of a velocity or a height off by one sigma is 1; a zero sigma adds no prior)."""
import gtsam
import numpy as np
import pytest
from gtsam.symbol_shorthand import V, X

from snake_autonomy.estimation.motion_model import GRAVITY_M_S2, MotionModel


def model(**kw):
    args = dict(velocity_sigma_m_s=0.5, height_sigma_m=0.05, still_gyro_rad_s=0.05, still_accel_m_s2=0.3,
                still_sigma_m_s=0.01)
    args.update(kw)
    return MotionModel(**args)


@pytest.mark.parametrize("gyro, accel, rest", [
    ((0.0, 0.01, 0.0), (0.0, 0.0, GRAVITY_M_S2), True),
    ((0.0, 0.0, 0.04), (0.2, 0.0, GRAVITY_M_S2 + 0.1), True),
    ((0.0, 0.0, 0.2), (0.0, 0.0, GRAVITY_M_S2), False),          # the head turning
    ((0.0, 0.0, 0.0), (0.0, 0.0, GRAVITY_M_S2 + 0.5), False),    # accelerating
])
def test_a_sample_is_at_rest_within_the_gyro_and_specific_force_limits(gyro, accel, rest):
    assert model().at_rest(gyro, accel) is rest


def test_rest_is_never_detected_when_turned_off():
    m = model(still_gyro_rad_s=0.0)
    assert not m.detects_rest and not m.at_rest((0.0, 0.0, 0.0), (0.0, 0.0, GRAVITY_M_S2))


def _whitened(factor, values) -> float:
    return float(np.sqrt(2.0 * factor.error(values)))


def test_the_priors_pull_velocity_and_height_with_their_sigmas():
    m = model()
    predicted = gtsam.Pose3(gtsam.Rot3.Yaw(0.7), np.array([1.0, 2.0, 0.3]))
    velocity_prior, height_prior = m.priors(4, predicted, height_m=0.25)
    values = gtsam.Values()
    values.insert(V(4), np.array([0.0, 0.5, 0.0]))                            # one sigma
    values.insert(X(4), gtsam.Pose3(gtsam.Rot3.Yaw(0.7), np.array([5.0, -3.0, 0.30])))
    assert _whitened(velocity_prior, values) == pytest.approx(1.0, rel=1e-6)
    # 5 cm above height_m: one sigma; the horizontal position (4 m and 5 m off) costs nothing
    assert _whitened(height_prior, values) == pytest.approx(1.0, rel=1e-3)
    still = m.still_factor(4)
    assert _whitened(still, values) == pytest.approx(50.0, rel=1e-6)           # 0.5 m/s at 1 cm/s


def test_a_zero_sigma_adds_no_prior():
    predicted = gtsam.Pose3()
    assert len(model(velocity_sigma_m_s=0.0).priors(1, predicted, 0.0)) == 1
    assert len(model(height_sigma_m=0.0).priors(1, predicted, 0.0)) == 1
    assert model(velocity_sigma_m_s=0.0, height_sigma_m=0.0).priors(1, predicted, 0.0) == []
