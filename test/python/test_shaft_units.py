"""One conversion between shaft states and raw control-table values (sim/servo_backend.ShaftUnits),
by the servo model's own table: with a servo of another resolution the batch driver still measures
the plant's joint angles (the driver's Transmission and the simulated bus read the same table).
The batch path once wrote Present Position with the XH540's 4096 ticks per turn whatever the table."""
import re

import numpy as np

from snake_autonomy import _core
from snake_autonomy.runs.batch import LockStepDriver, load_driver_config
from snake_autonomy.sim.config import SimConfig
from snake_autonomy.sim.plant import Plant
from snake_autonomy.sim.servo_backend import ShaftState, ShaftUnits

XH540_DEG_PER_TICK = 0.087890625


def high_resolution_table(root, tmp_path):
    """The XH540's table at 8192 ticks per turn, centre 4096 (a made-up servo model)."""
    text = (root / "config/dynamixel/xh540_w270.yaml").read_text()
    text = text.replace(f"scale: {XH540_DEG_PER_TICK}", f"scale: {XH540_DEG_PER_TICK / 2}")
    text = text.replace("position_centre_ticks: 2048", "position_centre_ticks: 4096")
    text = re.sub(r"(max_position_limit: .*default: )4095(, min: 0, max: )4095", r"\g<1>8191\g<2>8191", text)
    text = re.sub(r"(min_position_limit: .*max: )4095", r"\g<1>8191", text)
    text = re.sub(r"(goal_position: .*default: )2048(, min: 0, max: )4095", r"\g<1>4096\g<2>8191", text)
    text = re.sub(r"(present_position: .*default: )2048", r"\g<1>4096", text)
    path = tmp_path / "hires.yaml"
    path.write_text(text)
    return path


def test_shaft_units_follow_the_table(root, tmp_path):
    xh = ShaftUnits(_core.dynamixel.ControlTable.from_yaml(str(root / "config/dynamixel/xh540_w270.yaml")))
    hi = ShaftUnits(_core.dynamixel.ControlTable.from_yaml(str(high_resolution_table(root, tmp_path))))
    st = ShaftState(position_rad=0.5, velocity_rad_s=0.0, current_a=0.0)
    assert xh.present(st)[0] == 2048 + round(0.5 / np.radians(XH540_DEG_PER_TICK))
    assert hi.present(st)[0] == 4096 + round(0.5 / np.radians(XH540_DEG_PER_TICK / 2))
    assert hi.goal_rad(hi.present(st)[0]) == np.radians(XH540_DEG_PER_TICK / 2) * (hi.present(st)[0] - 4096)


def test_batch_driver_measures_the_plant_with_another_resolution(root, tmp_path):
    robot = _core.RobotModel.from_yaml(str(root / "config/robots/cobra.yaml"))
    params = SimConfig.from_yaml(root / "config/sim.yaml").draw(0, num_joints=robot.num_joints)
    q0 = np.radians(np.linspace(-20.0, 20.0, robot.num_joints))
    plant = Plant(robot, params, q0_rad=q0)
    plant.step(0.5)
    library = _core.GaitLibrary.from_yaml(str(root / "config/gaits.yaml"))
    driver = LockStepDriver(robot, library, plant, load_driver_config(root / "config/driver.yaml"),
                            control_table=str(high_resolution_table(root, tmp_path)))
    driver.update(plant.time_s, 0.01)
    one_tick = np.radians(XH540_DEG_PER_TICK / 2)
    assert np.allclose(driver.controller.position_rad, plant.joint_positions_rad(), atol=one_tick)
    assert np.ptp(plant.joint_positions_rad()) > 0.4          # a posture to measure, not all zeros
