"""The yaw moving average (section 3.2.2) and the blend weight w(d) (eq. 3.33)."""
import math

import pytest

from snake_autonomy.control import YawMovingAverage, blend_weight, smoothstep

DEG = math.pi / 180.0


@pytest.mark.parametrize("d,w", [(-0.1, 1.0), (0.0, 1.0), (0.25, 0.75), (0.5, 0.5), (0.75, 0.5), (1.0, 0.5),
                                 (1.25, 0.25), (1.5, 0.0), (2.0, 0.0), (1e6, 0.0)])
def test_weight_values(d, w):
    assert blend_weight(d) == pytest.approx(w, abs=1e-12)


@pytest.mark.parametrize("b", [0.0, 0.5, 1.0, 1.5])
def test_weight_is_continuous_with_flat_slope_at_each_breakpoint(b):
    h = 1e-6
    left = blend_weight(b - h) if b > 0 else 1.0
    right = blend_weight(b + h)
    assert abs(right - blend_weight(b)) < 1e-9
    assert abs(left - blend_weight(b)) < 1e-9
    # C1: one-sided slopes are both ~0 (a linear ramp would give |slope| = 1 or 2 per metre)
    assert abs((right - blend_weight(b)) / h) < 1e-4
    assert abs((blend_weight(b) - left) / h) < 1e-4


def test_weight_is_monotone_non_increasing():
    ds = [i * 0.01 for i in range(200)]
    ws = [blend_weight(d) for d in ds]
    assert all(a >= b for a, b in zip(ws, ws[1:]))


def test_smoothstep():
    assert [smoothstep(t) for t in (-1.0, 0.0, 0.5, 1.0, 2.0)] == [0.0, 0.0, 0.5, 1.0, 1.0]


def test_filter_averages_the_last_ten():
    f = YawMovingAverage()
    for i in range(12):
        f.add(i * DEG)
    assert f.count == 10 and f.full
    assert f.value == pytest.approx(6.5 * DEG)   # mean of 2..11


def test_filter_is_continuous_across_pi():
    f = YawMovingAverage(10)
    for i in range(10):
        f.add((179.0 if i % 2 == 0 else -179.0) * DEG)
    # naive averaging gives 0; the unwrapped average is 180 deg
    assert abs(abs(f.value) - math.pi) < 1e-9


def test_filter_follows_a_heading_sweeping_through_pi():
    f = YawMovingAverage(10)
    out = []
    for i in range(40):
        yaw = math.atan2(math.sin((170 + i) * DEG), math.cos((170 + i) * DEG))
        out.append(f.add(yaw))
    # after the window has filled, the filter lags the input by 4.5 samples (4.5 deg), never jumps
    for i in range(10, 40):
        expected = (170 + i - 4.5) * DEG
        assert math.cos(out[i] - expected) == pytest.approx(1.0, abs=1e-9)
    assert -math.pi <= min(out) and max(out) <= math.pi


def test_filter_reset_and_bad_input():
    f = YawMovingAverage(3)
    assert f.value is None
    f.add(1.0)
    f.reset()
    assert (f.value, f.count) == (None, 0)
    with pytest.raises(ValueError, match="yaw_rad: must be finite, got nan"):
        f.add(float("nan"))
    with pytest.raises(ValueError, match="window: must be a positive integer, got 0"):
        YawMovingAverage(0)
