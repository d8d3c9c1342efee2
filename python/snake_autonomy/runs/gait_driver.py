"""A gait of config/gaits.yaml driven through the C++ driver on a plant, in lock-step:
the batch simulator's LockStepDriver (the DriverController driver_node runs) with the base pose
from the plant's ground truth, for runs that command one gait with a steering value and no mission.

    drive = PlantGaitDriver(robot, plant)                  # starts holding at plant.time_s
    drive.command("rectilinear", kappa_per_m=0.5)          # curve=True for gaits with steering: curvature
    for k in range(n):
        drive.step(t, dt)                                   # base pose -> driver update -> joint targets
        t += dt; plant.step_to(t)

The command is re-sent every resend_s (the driver stops a gait left without commands for
command_timeout_s, config/driver.yaml); a refused command raises with the driver's reasons.
"""
from typing import Optional

from snake_autonomy import _core
from snake_autonomy.paths import config_path
from snake_autonomy.runs.batch import LockStepDriver, load_driver_config


class PlantGaitDriver:
    def __init__(self, robot, plant, gaits: Optional[str] = None, driver_config: Optional[str] = None,
                 resend_s: float = 1.0):
        self.plant = plant
        library = _core.GaitLibrary.from_yaml(str(gaits or config_path("gaits.yaml")))
        self.driver = LockStepDriver(robot, library, plant,
                                     load_driver_config(str(driver_config or config_path("driver.yaml"))))
        self.resend_s = float(resend_s)
        self._command = None
        self._sent_t = None

    def command(self, gait: str, kappa_per_m: Optional[float] = None, steer_delta_rad: Optional[float] = None,
                bias_rad=None) -> None:
        """The gait to run: kappa_per_m -> curve=True (curvature steering), steer_delta_rad -> steer=True
        (amplitude modulation), neither -> the gait as it is; bias_rad: one bias per joint replacing
        the gait's (follow-the-leader curvature, nav_batch). Sent at the next step."""
        self._command = (gait, kappa_per_m, steer_delta_rad, () if bias_rad is None else tuple(bias_rad))
        self._sent_t = None

    @property
    def gait(self) -> Optional[str]:
        """The commanded gait (None before a command)."""
        return None if self._command is None else self._command[0]

    @property
    def kappa_per_m(self) -> Optional[float]:
        """The commanded curvature (None before a command or without curvature steering)."""
        return None if self._command is None else self._command[1]

    def step(self, t_s: float, dt_s: float) -> None:
        pos, quat = self.plant.frame_pose("base_link")
        self.driver.set_base_pose(t_s, pos, quat)
        if self._command is not None and (self._sent_t is None or t_s - self._sent_t >= self.resend_s - 1e-9):
            gait, kappa, delta, bias = self._command
            why = self.driver.command_gait(gait, steer=delta is not None, delta_rad=delta or 0.0,
                                           curve=kappa is not None, kappa_per_m=kappa or 0.0, bias=bias)
            if why:
                raise RuntimeError(f"the driver refused {gait} (kappa {kappa}, delta {delta}): {why}")
            self._sent_t = t_s
        self.driver.update(t_s, dt_s)
