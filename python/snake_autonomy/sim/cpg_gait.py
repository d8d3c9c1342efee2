"""A gait of the library played open-loop through the core's CPG: the joint goals of the plant
checks and benchmarks, as the driver would send them (thesis 3.5, eq. 3.21-3.26).

    gait = CpgGait(robot, library, "sidewind", delta_rad=0.1)
    q = gait.joint_angles(robot, t_s)     # the CPG stepped forward to t_s (monotonic)

The CPG starts on its limit cycle (phases, amplitudes and biases of the gait), so there is no
start-up transient in the figures; steering modulates the yaw amplitudes (_core.Steering).
"""
from snake_autonomy import _core


class CpgGait:
    def __init__(self, robot, library, name: str, delta_rad: float = 0.0, step_s: float = 0.01):
        self.name = name
        self.frequency_hz = library.frequency_hz(name)
        self.step_s = step_s
        params = library.parameters(name, robot)
        if delta_rad:
            if not library.steerable(name):
                raise ValueError(f"gait {name!r} is not steerable")
            params.amplitude = _core.Steering(robot).modify_amplitudes(params.amplitude, delta_rad)
        self.cpg = _core.CPG(robot)
        self.cpg.reset(params.phase, params.amplitude, params.bias)
        self.cpg.apply(params)
        self._t = 0.0
        self._q = self.cpg.output

    def joint_angles(self, robot, t_s: float):
        """Joint goals (rad, within the joint limits) at t_s, stepping the CPG in step_s steps."""
        while self._t < t_s - 1e-9:
            self._q = self.cpg.step(self.step_s)
            self._t += self.step_s
        return self._q
