"""The one-parameter cubic (eq. 3-8, ERRATA #10) and the signs of the cost terms (eq. 12-15,
ERRATA #9)."""
import numpy as np
import pytest

from snake_autonomy.planning.fbsr import spline
from snake_autonomy.planning.fbsr.cost import (Directive, Pipe, head_clearance, pipe_cost, pipe_wall_overlap,
                                               stability_cost)


def test_cubic_starts_at_theta0_ends_at_rest_and_a_is_minus_2b_over_3_tend():
    theta0, delta, t_end = np.array([0.2, -0.5, 0.0]), np.array([0.6, 0.3, -1.0]), 2.5
    a, b = spline.coefficients(delta, t_end)
    np.testing.assert_allclose(a, -2 * b / (3 * t_end))
    np.testing.assert_allclose(spline.positions(theta0, delta, t_end, [0.0])[0], theta0)
    np.testing.assert_allclose(spline.positions(theta0, delta, t_end, [t_end])[0], theta0 + delta)
    np.testing.assert_allclose(spline.velocities(delta, t_end, [0.0, t_end]), 0.0, atol=1e-12)
    # eq. 3 with c = 0, d = theta0 at an interior time
    t = 0.7
    np.testing.assert_allclose(spline.positions(theta0, delta, t_end, [t])[0],
                               a * t ** 3 + b * t ** 2 + theta0)


def test_cubic_is_monotonic_so_the_delta_bounds_keep_every_sample_within_the_limits():
    lower, upper = np.full(4, -1.5), np.full(4, 1.5)
    theta0 = np.array([1.4, -1.4, 0.0, 0.5])
    lo, hi = spline.delta_bounds(theta0, lower, upper, margin_rad=0.05)
    t = np.linspace(0, 3, 301)
    for delta in (lo, hi):
        q = spline.positions(theta0, delta, 3.0, t)
        assert np.all(q >= lower + 0.05 - 1e-12) and np.all(q <= upper - 0.05 + 1e-12)
        assert np.all(np.diff(q, axis=0) * np.sign(delta) >= -1e-12)


def test_pipe_cost_is_the_sum_of_squared_horizontal_distances_erratum_9():
    """Eq. 15 as printed, (x - qx)^2 - (y - qy)^2, gives 0 for a module at (qx + 1, qy + 1) and
    rewards moving away along y; the erratum's + gives 2 and rewards only the axis."""
    pipe = Pipe(1.0, 2.0, 0.05)
    assert pipe_cost([[2.0, 3.0]], pipe) == pytest.approx(2.0)
    assert pipe_cost([[1.0, 2.5]], pipe) > pipe_cost([[1.0, 2.1]], pipe) > pipe_cost([[1.0, 2.0]], pipe)
    assert pipe_cost([[1.0, 2.0]], pipe) == 0.0


def test_stability_cost_falls_inward_jumps_nowhere_and_rises_outward():
    ks, kout = 4000.0, 1000.0
    inside = stability_cost([0.002, 0.01, 0.03, 0.1], ks, kout)
    assert np.all(np.diff(inside) < 0) and inside[-1] < 0.05
    edge_in, edge_out = stability_cost([1e-6, -1e-6], ks, kout)
    assert edge_in == pytest.approx(np.pi / 2, abs=1e-6) and edge_out == pytest.approx(np.pi / 2, abs=1e-6)
    outside = stability_cost([-0.001, -0.01, -0.1], ks, kout)
    assert np.all(np.diff(outside) > 0) and np.all(outside > np.pi / 2)


def test_directive_is_lower_for_a_higher_head_and_for_a_closer_target():
    low, high = np.array([0, 0, 0.1]), np.array([0, 0, 0.4])
    assert Directive().cost(high) < Directive().cost(low)
    assert Directive(height_m=0.3).cost(np.array([0, 0, 0.29])) < Directive(height_m=0.3).cost(low)
    target = Directive(target_m=[0.1, 0.0, 0.3])
    assert target.cost(np.array([0.1, 0.0, 0.3])) == 0.0 < target.cost(high)


def test_pipe_wall_only_stops_modules_at_the_wall_above_the_mouth():
    pipe = Pipe(0.0, 0.0, radius_m=0.07, mouth_m=0.25, wall_m=0.01)
    r = 0.025
    frames = [[0.0, 0.0, 0.4],      # in the bore
              [0.07, 0.0, 0.4],     # in the wall: out by 2.5 cm inward
              [0.3, 0.0, 0.4],      # beside the pipe
              [0.07, 0.0, 0.1]]     # under the mouth
    np.testing.assert_allclose(pipe_wall_overlap(frames, pipe, r), [0.0, 0.025, 0.0, 0.0])


def test_pipe_clearance_keeps_the_head_above_the_lip_that_far_inside_the_bore():
    """The bore's edge for a frame is 45 mm off the axis (R 70 mm less a 25 mm module); with a
    20 mm clearance the head (frame 0) 43 mm off it above the lip is 18 mm too far out; the
    modules behind it, there or under the lip, keep only the bore."""
    pipe = Pipe(0.0, 0.0, radius_m=0.07, mouth_m=0.25, wall_m=0.01)
    r, c = 0.025, 0.02
    arm = [[0.043, 0.0, 0.30],    # the head, 2 mm inside the bore's edge
           [0.043, 0.0, 0.27],    # the module behind it, as far out
           [0.043, 0.0, 0.20],    # under the lip
           [0.110, 0.0, 0.30]]    # beside the pipe
    np.testing.assert_allclose(pipe_wall_overlap(arm, pipe, r), [0.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(pipe_wall_overlap(arm, pipe, r, head_clearance(c, 4)),
                               [0.018, 0.0, 0.0, 0.0], atol=1e-12)
    centred = [[0.020, 0.0, 0.30]] + arm[1:]
    np.testing.assert_allclose(pipe_wall_overlap(centred, pipe, r, head_clearance(c, 4)), 0.0, atol=1e-12)
