"""Navigation runs on the simulated RTAB-Map (sim/nav_pose_source.py, runs/nav_batch.py --pose-source
vio): the loop's pose is off the truth by the odometry's noise and drift, bounded, and while tracking
is lost no pose comes and the loop holds the robot."""
import math

import numpy as np
import pytest

from snake_autonomy.paths import config_path
from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
from snake_autonomy.sim.world_file import load_world


def one_obstacle():
    return load_world(str(config_path("worlds") / "one_obstacle.yaml"))


def test_a_short_vio_run_has_a_pose_error_that_is_nonzero_and_bounded(sim_config_vio):
    sim = sim_config_vio(loss_rate_per_min=0.0)
    result = NavRun(NavRunSpec(one_obstacle(), pose_source="vio", time_limit_s=20.0, keep_frames=False,
                               sim_config=sim)).run()
    m = result.metrics
    assert m["pose_source"] == "vio" and m["pose_latency_s"] == pytest.approx(0.05)
    # 30 Hz odometry for 20 s, every sample through the gate
    assert 590 <= m["pose_samples"] <= 610 and m["pose_refused"] == 0 and m["tracking_lost_s"] == 0.0
    # white noise of 5-15 mm per axis plus a few mm of drift: not the truth, not far from it
    assert 0.002 < m["pose_error_xy_rmse_m"] < 0.03 and m["pose_error_xy_max_m"] < 0.08
    assert 0.0 < m["pose_error_yaw_max_deg"] < 5.0
    assert m["ticks_stale"] == 0 and m["replans"] == 2 and m["loop_errors"] == 0


def test_mocap_error_is_far_below_vio(tmp_path):
    m = NavRun(NavRunSpec(one_obstacle(), pose_source="mocap", time_limit_s=5.0, keep_frames=False)).run().metrics
    assert m["pose_source"] == "mocap" and m["pose_latency_s"] == pytest.approx(0.01)
    assert 0.0 < m["pose_error_xy_rmse_m"] < 0.002 and m["tracking_lost_s"] == 0.0


def test_the_loop_holds_while_tracking_is_lost_and_moves_again_after(sim_config_vio):
    """Tracking lost from 6 to 10 s: no pose reaches the loop; after its pose_timeout_s (1 s) every
    tick holds (state stale, the stop gait) until poses come again."""
    sim = sim_config_vio(loss_rate_per_min=0.0, loss_episodes=[[6.0, 4.0]])
    run = NavRun(NavRunSpec(one_obstacle(), pose_source="vio", time_limit_s=16.0, keep_frames=False,
                            sim_config=sim))
    result = run.run()
    m = result.metrics
    assert m["tracking_lost_s"] == pytest.approx(4.0, abs=0.1) and m["tracking_lost_episodes"] == 1
    by_t = {round(t, 2): (gait, state) for t, gait, _, state in result.commands}
    stop = run.gaits.command(True, False)
    for t in np.arange(7.5, 10.0, 0.5):     # pose older than 1 s (+ latency, + a tick's granularity)
        assert by_t[round(t, 2)] == (stop, "stale"), (t, by_t[round(t, 2)])
    assert by_t[5.5][1] == "following" and by_t[11.0][1] == "following"
    assert by_t[11.0][0] != stop
    assert m["ticks_stale"] == sum(1 for _, s in by_t.values() if s == "stale") >= 5
    # the hold keeps the robot in place: base_link moves less over the held seconds than while following
    traj = result.trajectory

    def moved(t0, t1):
        a, b = traj[np.argmin(abs(traj[:, 0] - t0))], traj[np.argmin(abs(traj[:, 0] - t1))]
        return math.hypot(b[1] - a[1], b[2] - a[2])
    assert moved(8.0, 10.0) < 0.5 * moved(13.0, 15.0)


def test_bad_pose_source_and_depth_model_are_refused():
    with pytest.raises(ValueError, match="pose_source: expected one of mocap, truth, vio, vo, got 'gps'"):
        NavRunSpec(one_obstacle(), pose_source="gps").check()
    with pytest.raises(ValueError, match="depth_model: expected one of noisy, perfect, got 'fuzzy'"):
        NavRunSpec(one_obstacle(), depth_model="fuzzy").check()
