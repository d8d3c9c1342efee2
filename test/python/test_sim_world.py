"""SimWorld (sim/world.py), the world both run paths step: sensors on their grids, the mission's
triggers and pushes on command, the monitor, ground truth and obstacles passed through to the plant.
(That the batch and ROS paths agree on it: test_sim_batch.py and the sim rostest.)"""
import math

import numpy as np
import pytest

from snake_autonomy.sim.world import SimWorld, WorldSpec

MISSION = """name: push_test
waypoints:
  - [3.0, 0.0, 0.0]
disturbances:
  - {time_s: 0.2, link: link_6, force_n: [0, 200, 0], duration_s: 0.1}
"""


def test_sensors_sample_on_their_grids_with_ground_truth():
    world = SimWorld(WorldSpec(seed=1, feedback="vio"))                   # default: mocap and the feedback's
    mocap = vio = 0
    for k in range(1, 101):
        out = world.step_to(k * 0.01)
        assert out.t_s == pytest.approx(k * 0.01)
        assert (out.mocap is None) == (out.truth_base is None) and (out.vio is None) == (out.truth_camera is None)
        mocap += out.mocap is not None
        vio += out.vio is not None
        if out.mocap is not None:
            assert np.linalg.norm(out.mocap.position_m - out.truth_base[0]) < 0.01
    assert mocap == 100 and vio == 31                                     # 30 Hz from t = 0: 0.01, 1/30, ..., 1.0
    only = SimWorld(WorldSpec(seed=1, feedback="mocap", sensors=("mocap",)))
    assert all(only.step_to(k * 0.01).vio is None for k in range(1, 20))
    with pytest.raises(ValueError, match="sensors: unknown"):
        SimWorld(WorldSpec(sensors=("lidar",)))
    with pytest.raises(ValueError, match="feedback"):
        SimWorld(WorldSpec(feedback="gps"))


def test_mission_trigger_fires_on_the_grid_and_records_the_recovery_window(tmp_path):
    path = tmp_path / "push.yaml"
    path.write_text(MISSION)
    world = SimWorld(WorldSpec(seed=0, mission=str(path)))
    assert len(world.triggers) == 1
    for k in range(1, 30):
        assert world.step_to(k * 0.01).fired == []                        # not armed before the mission starts
    world.start_mission(0.3)
    fired_at = None
    for k in range(30, 300):
        out = world.step_to(k * 0.01)
        if out.fired:
            fired_at = out.t_s
            assert "push" in out.fired[0] and "link_6" in out.fired[0]
    assert fired_at == pytest.approx(0.5)                                 # 0.2 s after the start, 10 Hz grid
    f = world.fired[0]
    assert f.mission_t_s == pytest.approx(0.2) and f.target_index == 0
    assert f.com_after is not None                                        # 2 s later
    moved = math.hypot(f.com_after[0] - f.com_before[0], f.com_after[1] - f.com_before[1])
    assert moved > 0.05                                                   # 20 N s on the 6 kg body, at rest before
    assert len(world.triggers) == 1                                       # the mission's list is kept


def test_pushes_on_command_monitor_and_status():
    world = SimWorld(WorldSpec(seed=0))
    with pytest.raises(ValueError, match="no such body"):
        world.disturb("tail_fin", force_n=[1, 0, 0])
    world.disturb("base_link", torque_nm=[40.0, 0.0, 0.0], duration_s=0.5)   # roll it over
    out = world.step_to(0.01)
    assert out.fired and "base_link" in out.fired[0]
    for k in range(2, 300):
        world.step_to(k * 0.01)
    s = world.status()
    assert s["rolled_over"] and world.rolled_over and s["max_tilt_deg"] > 90.0
    assert s["limit_violations"] == 0 and s["sim_time_s"] == pytest.approx(2.99)


def test_scene_xml_and_start_pose_reach_the_plant():
    wall = '<geom name="wall" type="box" size="0.05 1 0.2" pos="2 0 0.2" contype="2" conaffinity="1"/>'
    world = SimWorld(WorldSpec(seed=0, start=(1.0, -0.5, 45.0), scene_xml=wall))
    assert "wall" in [world.plant.model.geom(i).name for i in range(world.plant.model.ngeom)]
    x, y, heading = world.true_com_pose()
    assert (x, y) == pytest.approx((1.0, -0.5), abs=0.01) and math.degrees(heading) == pytest.approx(45.0, abs=0.5)
