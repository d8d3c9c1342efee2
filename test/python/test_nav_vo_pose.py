"""Navigation runs on the visual-inertial odometry (sim/nav_pose_source.py, runs/nav_batch.py
--pose-source vo): the estimator vio_node runs, on its own camera's frames and the IMU, gives the loop
a pose near the truth on a world with the odometry floor while the robot moves; a world whose floor
the odometry cannot track on is refused before anything is built."""
import math

import pytest

from snake_autonomy.paths import config_path
from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
from snake_autonomy.sim.mjcf import OVERHEAD_LIGHT
from snake_autonomy.sim.scene import build_scene
from snake_autonomy.sim.world_file import load_world


def world(name):
    return load_world(str(config_path("worlds") / f"{name}.yaml"))


def test_a_short_vo_run_tracks_the_moving_robot_with_a_small_pose_error():
    run = NavRun(NavRunSpec(world("odometry_corridor"), pose_source="vo", time_limit_s=20.0, keep_frames=False))
    result = run.run()
    m = result.metrics
    assert m["pose_source"] == "vo" and m["pose_latency_s"] == pytest.approx(0.05)
    # 10 Hz frames from 2.3 s (after the gyro's 2 s calibration at rest): about 177, nearly every one's
    # odometry through the gate
    assert 170 <= m["vo_frames"] <= 180 and m["pose_samples"] >= 160
    assert m["tracking_lost_s"] < 1.0 and m["loop_errors"] == 0
    # the estimate is not the truth, and stays near it (measured: 2.6 cm RMSE)
    assert 0.002 < m["pose_error_xy_rmse_m"] < 0.06 and m["pose_error_xy_max_m"] < 0.15
    # the error is measured on a robot that moved under the loop's commands
    start, end = result.trajectory[0], result.trajectory[-1]
    assert math.hypot(end[1] - start[1], end[2] - start[2]) > 0.05
    assert m["ticks_stale"] <= 2


@pytest.mark.parametrize("name", ["corridor", "one_obstacle"])
def test_vo_on_a_world_without_the_odometry_floor_is_refused_naming_the_field_and_value(name):
    w = world(name)
    with pytest.raises(ValueError, match=r"floor_texture 'carpet'.*vo needs floor_texture dots"):
        NavRun(NavRunSpec(w, pose_source="vo", time_limit_s=5.0, keep_frames=False))


def test_a_plain_floor_is_refused_for_vo_and_accepted_for_mocap():
    w = world("one_obstacle")
    w.floor_texture = "plain"
    with pytest.raises(ValueError, match=r"pose_source vo: .* floor_texture 'plain'"):
        NavRunSpec(w, pose_source="vo").check()
    NavRunSpec(w, pose_source="mocap").check()


def test_only_a_world_with_the_odometry_floor_is_lit_without_the_shadow_casting_light():
    odometry = build_scene(world("odometry_corridor"))
    assert OVERHEAD_LIGHT not in odometry.scene_xml and 'castshadow="true"' not in odometry.scene_xml
    assert 'mark="random"' in odometry.assets_xml.split("obstacle_tex_0", 1)[1]
    assert OVERHEAD_LIGHT in build_scene(world("corridor")).scene_xml
