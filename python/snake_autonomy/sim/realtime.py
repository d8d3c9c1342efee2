"""The simulated robot in real time, behind the mocked servo bus: what sim_node wraps (ROS-free).

    sim = RealTimeSim(SimSetup(feedback="vio", port="/tmp/snake_sim_bus", seed=0))
    sim.start()                        # the pty answers Protocol 2.0 from now on (the C++ driver's port)
    out = sim.step(time.monotonic())   # physics up to now; the sensor samples that fell due (WorldStep)

The world (plant, sensors, disturbances, monitor, ground truth) is sim.world.SimWorld, the one the
batch runner steps; here its clock is the bus's (time.monotonic): the mocked bus steps the physics
before each reply, step() whenever it is called (so sensors stay live while the driver is quiet),
and the transport is the mocked Protocol 2.0 bus on a pty instead of the batch's in-process bus.
"""
import time
from dataclasses import dataclass
from typing import Optional, Tuple

from .mock_servo_bus import MockServoBus
from .world import SimWorld, WorldSpec, WorldStep


@dataclass
class SimSetup(WorldSpec):
    """The world (sim.world.WorldSpec: seed, feedback, start, mission for its disturbances,
    sim_config, robot, tracker_config, scene_xml) plus the mocked bus's port."""
    port: str = "/tmp/snake_sim_bus"
    control: Optional[str] = None              # control socket (default port + ".ctl")


class RealTimeSim:
    def __init__(self, setup: SimSetup):
        self.setup = setup
        self.world = SimWorld(setup)
        w = self.world
        self.config, self.robot, self.params, self.plant, self.backend = w.config, w.robot, w.params, w.plant, w.backend
        self.bus = MockServoBus(self.backend, list(self.robot.servo_ids))

    # ---- lifecycle -------------------------------------------------------------------------------
    def start(self):
        self.bus.start(self.setup.port, self.setup.control or f"{self.setup.port}.ctl")
        return self

    def stop(self):
        self.bus.stop()

    def wait_bus_idle(self, quiet_s: float = 0.3, timeout_s: float = 5.0, clock=time.monotonic) -> bool:
        """Keeps serving the bus until no packet arrived for quiet_s (the driver has stopped talking:
        its final shutdown write is in) or timeout_s passed; True when it went quiet. Call before
        stop() when everything shuts down at once (Ctrl+C of a launch): the driver's shutdown action
        needs the bus."""
        start = last_change = clock()
        last = self.bus.stats()["packets"]
        while clock() - start < timeout_s:
            time.sleep(0.02)
            now, packets = clock(), self.bus.stats()["packets"]
            if packets != last:
                last, last_change = packets, now
            elif now - last_change >= quiet_s:
                return True
        return False

    # ---- inputs ----------------------------------------------------------------------------------
    def set_target(self, waypoint_index: int) -> None:
        """The tracker's active waypoint (tracking_status): arms the mid-leg disturbance triggers."""
        self.world.set_target(waypoint_index)

    def disturb(self, link: str, force_n=None, torque_nm=None, duration_s: float = 0.1) -> None:
        """A push or twist now (next physics step); ValueError for an unknown body."""
        self.world.disturb(link, force_n, torque_nm, duration_s)

    # ---- the step --------------------------------------------------------------------------------
    def watch_tail(self, on: bool) -> None:
        """While a scout trajectory raises the head on purpose (the driver's trajectory status says so),
        the roll-over check watches the tail's tilt instead of base_link's (as the batch path does)."""
        with self.world.lock:
            self.world.watch_tail(on)

    def step(self, now_s: float) -> WorldStep:
        with self.world.lock:
            self.backend.advance_locked(now_s)
            return self.world.observe()

    def true_com_pose(self) -> Tuple[float, float, float]:
        """Centre of mass and heading (direction of travel) from the true base pose (lock held)."""
        return self.world.true_com_pose()

    def status(self) -> dict:
        return {**self.world.status(), "paused_s": self.backend.paused_s}
