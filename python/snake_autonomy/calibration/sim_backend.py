"""The calibration's simulated robot: the batch simulator's world and driver, in lock-step.

    robot = SimRobot(seed=0)                    # config/sim.yaml, cobra.yaml, gaits.yaml, driver.yaml
    outcome = run_plan(robot, plan)             # sequence.run_plan: the same sequence as on the robot

Every 10 ms of simulated time: SimWorld.step_to (plant, sensors, monitor) -> the pose source
(motion capture, or the simulated RTAB-Map through the gate and eq. 3.1) -> the C++
DriverController (LockStepDriver) -> com_pose, which next_pose returns: the driver's centre of mass
and virtual chassis yaw, exactly what the tracker would see. A roll-over raises RuntimeError.
"""
import math
from typing import Optional, Tuple

from snake_autonomy import _core

from snake_autonomy.runs.batch import DRIVER_RATE_HZ, LockStepDriver, load_driver_config
from ..sim.feedback import make_feedback
from ..sim.world import CONFIG, SimWorld, WorldSpec


class SimRobot:
    def __init__(self, seed: int = 0, feedback: str = "mocap", sim_config: str = str(CONFIG / "sim.yaml"),
                 robot: str = str(CONFIG / "robots" / "cobra.yaml"), gaits: str = str(CONFIG / "gaits.yaml"),
                 driver_config: str = str(CONFIG / "driver.yaml"), randomize: bool = True):
        self.model = _core.RobotModel.from_yaml(robot)
        self.library = _core.GaitLibrary.from_yaml(gaits)
        self.world = SimWorld(WorldSpec(seed=seed, feedback=feedback, sim_config=sim_config, robot=robot,
                                        randomize=randomize, sensors=(feedback,)), robot=self.model)
        self.driver = LockStepDriver(self.model, self.library, self.world.plant, load_driver_config(driver_config))
        self.feedback = make_feedback(feedback, self.world.params, self.model)
        self.dt_s = 1.0 / DRIVER_RATE_HZ
        self._k = int(round(self.world.plant.time_s * DRIVER_RATE_HZ))

    @property
    def time_s(self) -> float:
        return self._k * self.dt_s

    def period_s(self, gait: str) -> float:
        return 1.0 / self.library.frequency_hz(gait)

    def command(self, gait: str, steer: bool, delta_rad: float) -> str:
        return self.driver.command_gait(gait, steer, delta_rad)

    def next_pose(self, timeout_s: float) -> Optional[Tuple[float, float, float, float]]:
        """Steps the world and the driver until the driver has a fresh com_pose (or timeout_s)."""
        steps = max(1, int(math.ceil(timeout_s * DRIVER_RATE_HZ)))
        for _ in range(steps):
            self._k += 1
            t = self.time_s
            out = self.world.step_to(t)
            pose = self.feedback.pose(out)
            if pose is not None:
                self.driver.set_base_pose(t, pose[1], pose[2])
            self.driver.update(t, self.dt_s)
            if self.world.rolled_over:
                raise RuntimeError(f"the simulated robot rolled over at {t:.1f} s (tilt {out.tilt_deg:.0f} deg)")
            com = self.driver.com_pose()
            if com is not None:
                return (t,) + tuple(com)
        return None
