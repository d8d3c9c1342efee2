"""Ventral scales on the simulated robot: directional friction on the links touching the floor
(config/sim.yaml `scales:`), for gaits that rely on frictional anisotropy (rectilinear, Chang et
al.'s robot "with scales").

MuJoCo's contacts stay isotropic Coulomb, with the floor's coefficient lowered to forward_friction
(for the floor and every robot geom: MuJoCo takes the larger of the two). On each physics step,
for each robot geom touching the floor with normal force N, a force at the contact point adds
    (backward_friction - forward_friction) N sat(v_f)   against sliding towards the tail, and
    (lateral_friction - forward_friction) N sat(v_l)    against sliding sideways,
v_f, v_l: the contact point's horizontal velocity along the link's axis (+ towards the head) and
across it; sat(v) = v / sqrt(v^2 + eps^2) with eps = regularisation_m_s (smooth near zero speed).
They act on the link's axis above the contact point (no roll torque). The forces go through
qfrc_applied (the plant's pushes use xfrc_applied). Stepping is one physics
step at a time (about 2-3x slower than the plain plant).
"""
import math

import mujoco
import numpy as np

from .plant import Plant


class ScaledPlant(Plant):
    """A Plant with ventral scales when params.config.scales.enabled (otherwise a plain Plant)."""

    def __init__(self, robot, params, *args, **kwargs):
        super().__init__(robot, params, *args, **kwargs)
        self.scales = params.config.scales
        m = self.model
        self._floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        self._robot_geom = np.array([m.geom_bodyid[g] != 0 for g in range(m.ngeom)])
        if self.scales.enabled:
            m.geom_friction[self._robot_geom, 0] = self.scales.forward_friction
            m.geom_friction[self._floor, 0] = self.scales.forward_friction
        self._force6 = np.zeros(6)
        self._zero3 = np.zeros(3)

    def step_to(self, t_s: float) -> None:
        if not self.scales.enabled:
            return super().step_to(t_s)
        target = int(math.floor(t_s / self.dt_s + 1e-9))
        while self._steps < target:
            self._apply_scales()
            super().step_to((self._steps + 1) * self.dt_s)

    def _apply_scales(self) -> None:
        m, d, sc = self.model, self.data, self.scales
        d.qfrc_applied[:] = 0.0
        d_back = sc.backward_friction - sc.forward_friction
        d_lat = sc.lateral_friction - sc.forward_friction
        eps2 = sc.regularisation_m_s ** 2
        vel = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            if g1 == self._floor and self._robot_geom[g2]:
                g = g2
            elif g2 == self._floor and self._robot_geom[g1]:
                g = g1
            else:
                continue
            mujoco.mj_contactForce(m, d, i, self._force6)
            normal = float(self._force6[0])
            if normal <= 0:
                continue
            body = int(m.geom_bodyid[g])
            axis = d.xmat[body].reshape(3, 3)[:, 0]
            e = np.array([axis[0], axis[1], 0.0])
            n = np.linalg.norm(e)
            if n < 1e-6:
                continue
            e /= n
            lat = np.array([-e[1], e[0], 0.0])
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, g, vel, 0)
            # velocity of the contact point: geom centre's linear + angular x (point - centre)
            v = vel[3:] + np.cross(vel[:3], c.pos - d.geom_xpos[g])
            vf, vl = float(v @ e), float(v @ lat)
            f = np.zeros(3)
            if vf < 0:
                f -= d_back * normal * vf / math.sqrt(vf * vf + eps2) * e
            f -= d_lat * normal * vl / math.sqrt(vl * vl + eps2) * lat
            # applied on the link's axis above the contact: no roll torque (scales acting at the
            # belly roll a round link over: measured, the straight gait rolled COBRA onto its side)
            point = np.array([c.pos[0], c.pos[1], d.geom_xpos[g][2]])
            mujoco.mj_applyFT(m, d, f, self._zero3, point, body, d.qfrc_applied)
