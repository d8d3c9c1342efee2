"""The rectilinear gait of config/gaits.yaml through the C++ driver (LockStepDriver: the
DriverController on the plant; command_gait rectilinear, curve + kappa) on the simulated COBRA with
nav runs' flat belly, against the Python reference's gait map (planning/rectilinear/gait.py,
config/gait_maps/cobra_rectilinear.yaml: 7.2 mm/s straight at A 2 cm, flat belly 0.8)."""
import dataclasses
import math

import pytest
import yaml

RAMP_S = 5.0          # hold -> rectilinear: the CPG's amplitudes converge (gamma 2 rad/s) in ~2 s
MEASURE_CYCLES = 4    # 10 s at 0.4 Hz; each run 15 s of physics, two runs


def _run(root, kappa_per_m):
    from snake_autonomy import _core
    from snake_autonomy.sim.config import SimConfig
    from snake_autonomy.runs.gait_driver import PlantGaitDriver
    from snake_autonomy.runs.gait_map import body_velocity, stroboscopic_sample
    from snake_autonomy.sim.scales import ScaledPlant
    nav = yaml.safe_load((root / "config" / "nav.yaml").read_text())
    robot = _core.RobotModel.from_yaml(str(root / "config" / "robots" / "cobra.yaml"))
    cfg = SimConfig.from_yaml(str(root / "config" / "sim.yaml"))
    cfg = dataclasses.replace(cfg, physics=dataclasses.replace(
        cfg.physics, flat_belly_fraction=nav["plant"]["flat_belly_fraction"]))
    plant = ScaledPlant(robot, cfg.draw(seed=0, num_joints=robot.num_joints, randomize=False), (0.0, 0.0, 0.0))
    drive = PlantGaitDriver(robot, plant)
    drive.command("rectilinear", kappa_per_m=kappa_per_m)
    period, dt, t = 1.0 / 0.4, 0.01, 0.0
    samples = []
    for cycle in range(MEASURE_CYCLES + 1):
        t_end = RAMP_S + cycle * period
        while t < t_end - 1e-9:
            drive.step(t, dt)
            t += dt
            plant.step_to(t)
        samples.append(stroboscopic_sample(plant))
    assert drive.driver.controller.state == "running"
    assert plant.base_tilt_deg() < 30.0
    return body_velocity(samples, MEASURE_CYCLES * period)


def test_the_driver_gait_matches_the_python_reference(root):
    ref = yaml.safe_load((root / "config" / "gait_maps" / "cobra_rectilinear.yaml").read_text())
    fit = next(f for f in ref["fits"] if f["amplitude"] == 0.02)
    v_ref = fit["speed_straight_m_s"]
    assert v_ref == pytest.approx(0.0072, abs=0.0005)      # the README's figure
    vx, vy, w = _run(root, 0.0)
    print(f"driver rectilinear straight: xi_x {vx * 1000:.2f} mm/s (reference {v_ref * 1000:.2f}), "
          f"xi_y {vy * 1000:.2f} mm/s, w {math.degrees(w):.3f} deg/s")
    assert vx > 0.0                                         # head first
    assert vx == pytest.approx(v_ref, rel=0.25)
    vx1, vy1, w1 = _run(root, 1.0)
    print(f"driver rectilinear kappa 1/m: xi_x {vx1 * 1000:.2f} mm/s, w {math.degrees(w1):.3f} deg/s "
          f"(reference fit {math.degrees(fit['omega_per_steer']):.3f} deg/s)")
    assert w1 > 0.2 * fit["omega_per_steer"] > 0.0           # kappa > 0 turns left (CCW)
    assert vx1 > 0.0
