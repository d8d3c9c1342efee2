"""Ventral scales (sim/scales.py, config/sim.yaml scales:): directional friction on the plant."""
import dataclasses

import numpy as np
import pytest

from snake_autonomy.sim.config import SimConfig


@pytest.fixture(scope="module")
def setup(root):
    from snake_autonomy import _core
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    return robot, SimConfig.from_yaml(str(root / "config" / "sim.yaml"))


def test_scales_config_is_checked():
    cfg = SimConfig.from_dict({"scales": {"enabled": True, "backward_friction": 1.0}})
    assert cfg.scales.enabled and cfg.scales.backward_friction == 1.0
    with pytest.raises(ValueError, match="scales.lateral_friction: must be > 0, got -1"):
        SimConfig.from_dict({"scales": {"lateral_friction": -1.0}})
    with pytest.raises(ValueError, match="scales.colour: unknown key"):
        SimConfig.from_dict({"scales": {"colour": 1.0}})


def _push(robot, cfg, enabled, force_x):
    from snake_autonomy.sim.scales import ScaledPlant
    c = dataclasses.replace(cfg, scales=dataclasses.replace(cfg.scales, enabled=enabled))
    plant = ScaledPlant(robot, c.draw(seed=0, randomize=False), (0.0, 0.0, 0.0))
    plant.step_to(0.1)                       # settle on the floor
    x0 = plant.frame_positions()[:, 0].mean()
    for body in range(1, plant.model.nbody):
        plant.data.xfrc_applied[body, 0] = force_x * plant.model.body_mass[body]
    plant.step_to(0.6)
    return plant.frame_positions()[:, 0].mean() - x0


def test_scales_resist_sliding_tail_first_more_than_head_first(setup):
    robot, cfg = setup
    # 10 N/kg along the body: above forward friction (0.7 g), below backward (1.5 g)
    fwd_on, back_on = _push(robot, cfg, True, 10.0), _push(robot, cfg, True, -10.0)
    fwd_off, back_off = _push(robot, cfg, False, 10.0), _push(robot, cfg, False, -10.0)
    assert fwd_on > 0.2 and abs(back_on) < 0.03
    assert fwd_off == pytest.approx(-back_off, abs=0.02)     # isotropic without scales
    assert np.sign(fwd_off) == 1
