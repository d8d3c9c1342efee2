"""What keeps COBRA upright on the rectilinear gait (bench/nav_roll): the
follower's kappa rate limit, the flat-belly plant option (off by default), the gait map read by
nav.yaml's follower."""
import math

import mujoco
import pytest

from snake_autonomy import _core
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import FollowerParams, RecedingHorizonFollower
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.mjcf import build_mjcf

import numpy as np


def _follower(rate):
    f = RecedingHorizonFollower(FollowerParams(speed_m_s=0.01, omega_per_kappa=0.01, kappa_max_per_m=1.0,
                                               k_heading=1.0, kappa_rate_per_m_s=rate))
    # a path straight to the left of the robot: the heading feedback asks for the largest kappa
    f.set_path(np.array([[0.0, 0.01 * i, 0.0] for i in range(50)]), 0.0)
    return f


def test_the_follower_limits_the_rate_of_kappa():
    f = _follower(0.05)
    ks = [f.update(t, (0.0, 0.0, 0.0)).kappa_per_m for t in np.arange(0.0, 30.0, 0.5)]
    assert ks[0] == 0.0
    assert max(abs(b - a) for a, b in zip(ks, ks[1:])) <= 0.05 * 0.5 + 1e-12
    assert ks[-1] == pytest.approx(1.0)            # reaches the command (clipped to kappa_max)
    assert ks[10] == pytest.approx(0.25)           # 5 s at 0.05 /m/s
    unlimited = _follower(0.0)
    assert unlimited.update(0.0, (0.0, 0.0, 0.0)).kappa_per_m == pytest.approx(1.0)


def test_kappa_rate_must_not_be_negative():
    with pytest.raises(ValueError, match="kappa_rate_per_m_s: must be >= 0, got -1"):
        RecedingHorizonFollower(FollowerParams(kappa_rate_per_m_s=-1.0))


def _model(root, fraction):
    cfg = SimConfig.from_yaml(str(root / "config" / "sim.yaml"))
    assert cfg.physics.flat_belly_fraction == 0.0      # off for the thesis experiments
    import dataclasses
    cfg = dataclasses.replace(cfg, physics=dataclasses.replace(cfg.physics, flat_belly_fraction=fraction))
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    m = mujoco.MjModel.from_xml_string(build_mjcf(robot, cfg.draw(seed=0, randomize=False)))
    return m, mujoco.MjData(m), robot


def test_the_flat_belly_is_an_option_whose_bottom_is_flush_with_the_capsules(root):
    m, d, robot = _model(root, 0.0)
    assert sum(m.geom_type == mujoco.mjtGeom.mjGEOM_BOX) == 0
    mass = sum(m.body_mass)
    m, d, robot = _model(root, 0.8)
    boxes = np.nonzero(m.geom_type == mujoco.mjtGeom.mjGEOM_BOX)[0]
    assert len(boxes) == robot.num_joints + 1                 # head and every link
    assert sum(m.body_mass) == pytest.approx(mass)            # massless
    mujoco.mj_forward(m, d)
    r = robot.link_radius_m
    base_z = d.xpos[1][2]                                     # capsule axis height in the start pose
    for g in boxes:
        R = d.geom_xmat[g].reshape(3, 3)
        half = m.geom_size[g]
        bottom = d.geom_xpos[g][2] - abs(R[2]) @ half         # lowest point of the box
        assert bottom == pytest.approx(base_z - r, abs=1e-9)
        # flat and level: its own z axis vertical, 0.8 of the diameter wide
        assert abs(abs(R[2, 2]) - 1.0) < 1e-9
        assert half[1] == pytest.approx(0.8 * r)


def test_sim_yaml_refuses_a_flat_belly_outside_0_1(root, tmp_path):
    text = (root / "config" / "sim.yaml").read_text().replace("flat_belly_fraction: 0.0", "flat_belly_fraction: 1.5")
    bad = tmp_path / "sim.yaml"
    bad.write_text(text)
    with pytest.raises(ValueError, match=r"physics.flat_belly_fraction: must be in \[0, 1\], got 1.5"):
        SimConfig.from_yaml(str(bad))


def test_nav_config_reads_the_follower_keys_of_a_gait_map(tmp_path):
    gm = tmp_path / "gait_map.yaml"
    gm.write_text("follower: {speed_m_s: 0.0071, omega_per_kappa: 0.02, omega_offset_rad_s: 0.001}\n")
    cfg = NavConfig.from_dict({"follower": {"gait_map": str(gm), "kappa_max_per_m": 3.0}})
    assert cfg.follower.speed_m_s == 0.0071 and cfg.follower.omega_per_kappa == 0.02
    assert cfg.follower.kappa_max_per_m == 3.0          # the section's own keys win over the map's
    # a file's map stands over its base's follower keys; the file's own keys over the map
    (tmp_path / "base.yaml").write_text("follower: {speed_m_s: 0.5, omega_per_kappa: 0.9, k_heading: 0.3}\n")
    (tmp_path / "own.yaml").write_text(f"base: base.yaml\nfollower: {{gait_map: {gm}, omega_per_kappa: 0.04}}\n")
    own = NavConfig.from_yaml(tmp_path / "own.yaml").follower
    assert (own.speed_m_s, own.omega_per_kappa, own.omega_offset_rad_s, own.k_heading) == (0.0071, 0.04, 0.001, 0.3)
    with pytest.raises(NavConfigError, match="follower.gait_map: no such file 'nope.yaml'"):
        NavConfig.from_dict({"follower": {"gait_map": "nope.yaml"}})
    with pytest.raises(NavConfigError, match=r"plant.flat_belly_fraction: must be in \[0, 1\], got 2.0"):
        NavConfig.from_dict({"plant": {"flat_belly_fraction": 2.0}})
    assert math.isclose(NavConfig.from_yaml().plant.flat_belly_fraction, 0.8)


class _AllFree:
    def pose_state(self, poses, ground, scale=None):
        none = np.zeros(len(poses), dtype=bool)
        return none, none                    # nothing blocked, nothing unknown


def test_with_every_arc_free_the_goal_bias_takes_the_arc_passing_closest_to_the_goal():
    from snake_autonomy.planning.rectilinear.sampler import SamplerParams, TrajectorySampler
    s = TrajectorySampler(_AllFree(), SamplerParams(num_arcs=5, max_curvature_per_m=2.0, horizon_m=1.2,
                                                    goal_tie_m=0.3))
    # the goal 0.5 m ahead and 0.25 m to the right (a run without the bias drove past such a goal)
    sel = s.select(np.ones((4, 4), bool), (0.5, -0.25))
    assert sel.arc.curvature_per_m < 0
    assert s.select(np.ones((4, 4), bool), (0.5, 0.25)).arc.curvature_per_m > 0
    assert s.select(np.ones((4, 4), bool), (2.0, 0.0)).arc.curvature_per_m == 0.0
    # without the bias (the paper's rule) the least curvature wins among equally long arcs
    plain = TrajectorySampler(_AllFree(), SamplerParams(num_arcs=5, goal_tie_m=0.0))
    assert plain.select(np.ones((4, 4), bool), (0.5, -0.25)).arc.curvature_per_m == 0.0


def test_the_lateral_margin_must_not_be_negative():
    from snake_autonomy.planning.rectilinear.sampler import SamplerParams
    assert SamplerParams(lateral_margin_m=-0.1).validate() == ["lateral_margin_m: must be >= 0, got -0.1"]


class _FreeUpTo:
    """Straight arc free to its end, curved ones only to 0.6 m (the far floor unsure)."""
    def pose_state(self, poses, ground, scale=None):
        blocked = ~np.array([abs(y) < 1e-9 or x < 0.6 for x, y, _ in poses])
        return blocked, np.zeros(len(poses), dtype=bool)


def test_an_arc_free_beyond_the_goal_is_long_enough_for_the_goal_bias():
    from snake_autonomy.planning.rectilinear.sampler import SamplerParams, TrajectorySampler
    s = TrajectorySampler(_FreeUpTo(), SamplerParams(num_arcs=5, max_curvature_per_m=2.0, horizon_m=1.2,
                                                     goal_tie_m=0.3))
    assert s.select(np.ones((4, 4), bool), (0.4, 0.2)).arc.curvature_per_m > 0     # goal near: turn
    assert s.select(np.ones((4, 4), bool), (1.5, 0.4)).arc.curvature_per_m == 0.0  # goal far: longest
