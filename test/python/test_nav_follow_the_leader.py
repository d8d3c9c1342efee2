"""Follow-the-leader steering (planning/rectilinear/follow_the_leader.py, nav.yaml gaits.steering):
each yaw joint takes the curvature the head had where the joint is now, and the turn it changes
through the C++ driver (runs/turn_sweep.py, bench/nav_follow_the_leader)."""
import math

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear.follow_the_leader import FollowTheLeader


def _ftl():
    # three yaw joints 0.2 m apart, each bending over 0.2 m of path; 1 cm cells (a joint's mean is over
    # 21 cells: a cell at a span's end may go either way, 2/21 ~ 0.1 of 2 /m)
    return FollowTheLeader([0.0, 0.2, 0.4], 0.2, resolution_m=0.01, yaw_joints=[1, 3, 5], num_joints=6)


def test_each_joint_takes_the_heads_curvature_when_it_gets_where_the_head_was():
    f = _ftl()
    f.advance(0.3, 2.0)                       # the head crawls 0.3 m commanding 2 /m
    k = f.joint_kappas()
    assert k[0] == pytest.approx(2.0)         # the first joint's span (0.1..0.3 m) lies on the new curve
    assert k[1] == pytest.approx(1.0, abs=0.1)    # the second's (-0.1..0.1): half of it
    assert k[2] == 0.0                        # the third is still on the straight start
    f.advance(0.3, 0.0)                       # straight again for 0.3 m
    k = f.joint_kappas()
    assert k[0] == pytest.approx(0.0, abs=0.1) and k[1] == pytest.approx(1.0, abs=0.1)
    assert k[2] == pytest.approx(2.0, abs=0.1)     # the third now bends where the head turned
    b = f.biases()
    assert list(np.flatnonzero(b)) == [3, 5] and b[3] == pytest.approx(k[1] * 0.2)


def test_backing_off_retraces_the_track_and_lays_nothing_down():
    f = _ftl()
    f.advance(0.3, 2.0)
    f.advance(0.3, 0.0)
    before = f.joint_kappas()
    f.advance(-0.3, -3.0)                     # backing off: the joints take the path behind them again
    assert f.joint_kappas()[0] == pytest.approx(2.0, abs=0.1)
    f.advance(0.3, 0.0)                       # forward again over the same path: as before
    assert np.allclose(f.joint_kappas(), before)


def test_the_crawl_is_the_heads_move_along_its_heading():
    f = _ftl()
    f.crawl((0.0, 0.0, math.radians(90)), 1.0)
    f.crawl((0.05, 0.2, math.radians(90)), 1.0)          # 0.2 m along +y (heading 90 deg), 5 cm sideways
    assert f.s_head_m == pytest.approx(0.2)


def test_follow_the_leader_of_cobra_and_bad_input():
    from snake_autonomy import _core
    from snake_autonomy.paths import config_path
    robot = _core.RobotModel.from_yaml(str(config_path("robots", "cobra.yaml")))
    f = FollowTheLeader.of_robot(robot)
    assert f.yaw_joints == [1, 3, 5, 7, 9] and f.spacing_m == pytest.approx(2 * robot.link_length_m)
    assert f.offsets[-1] == pytest.approx(8 * robot.link_length_m)
    with pytest.raises(ValueError, match="joint_offsets_m: expected increasing offsets"):
        FollowTheLeader([0.2, 0.0], 0.2)
    with pytest.raises(ValueError, match="spacing_m and resolution_m must be > 0"):
        FollowTheLeader([0.0, 0.2], 0.0)


def test_a_bias_vector_of_the_wrong_length_is_refused_by_the_driver():
    from snake_autonomy import _core
    from snake_autonomy.paths import config_path
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.runs.gait_driver import PlantGaitDriver
    from snake_autonomy.sim.scales import ScaledPlant
    robot = _core.RobotModel.from_yaml(str(config_path("robots", "cobra.yaml")))
    plant = ScaledPlant(robot, SimConfig.from_yaml(str(config_path("sim.yaml"))).draw(seed=0, num_joints=11),
                        (0.0, 0.0, 0.0))
    drive = PlantGaitDriver(robot, plant)
    drive.command("rectilinear", bias_rad=[0.1, 0.2, 0.3])
    with pytest.raises(RuntimeError, match="bias"):
        drive.step(0.0, 0.01)


def test_follow_the_leader_keeps_cobras_body_on_the_heads_track_through_the_driver():
    """A 1.5 /m turn for 90 s on open floor (runs/turn_sweep.py, the gait through the C++ driver).
    Measured: uniform curvature swings the head 0.33 m sideways in the first 10 s and the body strays
    0.37 m from the head's track; follow-the-leader 0.02 m and 0.11 m, turning 56 deg against 65.
    About 13 s."""
    from snake_autonomy.runs.turn_sweep import turn_sweep
    uniform = turn_sweep("uniform")
    ftl = turn_sweep("follow_the_leader")
    assert uniform.head_sideways_m[0] > 0.25 and uniform.off_track_m > 0.3
    assert ftl.head_sideways_m[0] < 0.05 and ftl.off_track_m < 0.15
    assert ftl.heading_change_deg > 45 and uniform.heading_change_deg > 45
