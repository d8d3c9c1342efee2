"""The rectilinear gait's Python reference (planning/rectilinear/gait.py) on the plant."""
import math

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear.gait import RectilinearGait


@pytest.fixture(scope="module")
def cobra(root):
    from snake_autonomy import _core
    return _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))


def test_discretised_wave_and_curvature(cobra):
    g = RectilinearGait(amplitude_m=0.02, wavelength_m=1.0, frequency_hz=0.4)
    q = g.joint_angles(cobra, 0.3, kappa_per_m=1.5)
    axes = list(cobra.axes)
    yaw = [i for i, a in enumerate(axes) if a == "yaw"]
    pitch = [i for i, a in enumerate(axes) if a == "pitch"]
    # yaw joints: kappa x the yaw joints' spacing (2 L on COBRA)
    assert q[yaw] == pytest.approx([1.5 * 2 * cobra.link_length_m] * len(yaw))
    # pitch joints: the slope changes of the polyline through z(s); they sum to last - first slope
    s = np.concatenate([[0.0], cobra.head_length_m + cobra.link_length_m * np.array(pitch),
                        [cobra.head_length_m + cobra.link_length_m * 11]])
    z = 0.02 * np.sin(2 * math.pi * (0.4 * 0.3 + s / 1.0))
    slope = np.arctan2(np.diff(z), np.diff(s))
    assert q[pitch].sum() == pytest.approx(slope[-1] - slope[0])
    # the wave travels: a quarter period later the pattern differs, a full period later it repeats
    assert not np.allclose(g.joint_angles(cobra, 0.3 + 0.625), q)
    assert g.joint_angles(cobra, 0.3 + 2.5, 1.5) == pytest.approx(q)


def _displacement(cobra, root, gait, seconds=10.0):
    """The links' mean displacement over `seconds` of the gait after a 2 s ramp."""
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.sim.plant import Plant
    params = SimConfig.from_yaml(str(root / "config" / "sim.yaml")).draw(seed=0)
    plant = Plant(cobra, params, (0.0, 0.0, 0.0))
    t = 0.0
    while t < 2.0:
        plant.set_joint_targets(gait.joint_angles(cobra, 0.0) * t / 2.0)
        t += 0.01
        plant.step_to(t)
    start = plant.frame_positions().mean(axis=0)
    while t < 2.0 + seconds:
        plant.set_joint_targets(gait.joint_angles(cobra, t - 2.0))
        t += 0.01
        plant.step_to(t)
    return plant.frame_positions().mean(axis=0) - start, plant


def test_the_reversed_wave_backs_cobra_off_tail_first(cobra, root):
    """nav run --gait-source reference backs off (follower BACK_OFF) with direction negated, as the
    driver's gaits.yaml rectilinear_reverse negates the lag: the robot must then move tail first."""
    back, plant = _displacement(cobra, root, RectilinearGait(0.02, 1.0, 0.4, direction=-1.0))
    assert back[0] < -0.03                 # tail first (-x): measured 6.6 mm/s, forward 6.8
    assert abs(back[1]) < 0.01 and plant.base_tilt_deg() < 30


def test_cobra_moves_head_first_with_isotropic_friction(cobra, root):
    """The gait's wave travelling towards the head drives COBRA forward on the plant's isotropic
    Coulomb floor (measured: about 7 mm/s at A 2 cm, lambda 1 m, 0.4 Hz; bench/nav_gait)."""
    d, plant = _displacement(cobra, root, RectilinearGait(0.02, 1.0, 0.4))
    assert d[0] > 0.03                     # > 3 mm/s forward (+x: the head's direction)
    assert abs(d[1]) < 0.01 and plant.base_tilt_deg() < 30
