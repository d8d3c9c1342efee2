"""The scout run's monitor (runs/scout_execute.Monitor): a step with no floor pressure has no
centre of pressure — counted apart, not as "outside" — unless it lasts (then the robot is off the
floor: tipped), as run_plan decides."""
import numpy as np

from snake_autonomy import _core
from snake_autonomy.runs import scout_execute
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.plant import Plant


def monitor(root, monkeypatch, cops):
    robot = _core.RobotModel.from_yaml(str(root / "config/robots/cobra.yaml"))
    params = SimConfig.from_yaml(root / "config/sim.yaml").draw(0, num_joints=robot.num_joints)
    plant = Plant(robot, params)
    plant.step(0.3)
    m = scout_execute.Monitor(plant, params.config.servo.torque_limit_nm)
    real = scout_execute.floor_contacts
    for cop in cops:
        if cop == "real":
            monkeypatch.setattr(scout_execute, "floor_contacts", real)
        else:
            monkeypatch.setattr(scout_execute, "floor_contacts",
                                lambda *_a: (np.zeros((0, 2)), np.zeros(0), np.zeros(0, int)))
        m()
    return m


def test_a_step_without_pressure_is_counted_apart(root, monkeypatch):
    m = monitor(root, monkeypatch, ["real"] * 5 + [None] * 2 + ["real"] * 5)
    assert m.no_pressure_steps == 2 and m.longest_no_pressure == 2
    assert len(m.inside) == 10 and all(m.inside)      # the lying robot's CoP is inside its contacts


def test_a_long_stretch_without_pressure_is_counted_for_tipping(root, monkeypatch):
    m = monitor(root, monkeypatch, ["real"] + [None] * 12)
    assert m.longest_no_pressure * scout_execute.DRIVER_PERIOD_S > 0.1
