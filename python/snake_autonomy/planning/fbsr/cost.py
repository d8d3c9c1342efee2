"""The stage cost C = K1 Cd + K2 Cs + K3 Cp (paper eq. 9), plus the optional torque term the paper
suggests (III.D, last paragraph) and two penalties the paper's robot did not need written down:
no module below the floor, no module through another (collision.py: capsules of non-adjacent
modules pushed apart to the self-collision margin plus a push, which covers the servos' sag in
physics and the cost's few samples against the check's 50 ms; a pair that starts the stage
closer than that is pushed only to where it started).

- Cd, the directive (eq. 10-12): -z of the head at t_end; or the target forms: |z - H| for a
  head height H, |p - target| for a head position.
- Cs, stability (eq. 13-14): the integral over the trajectory of pi/2 - atan(Ks l^2) inside the
  polygon, l the ZMP's distance to the nearest edge. Outside, eq. 13 as printed adds l^2 to the
  same expression; its atan part then *falls* with l, which pushes a ZMP just outside further
  out, against the text's intent ("the added l^2 term ... provides a gradient leading back
  inside"). Here outside is pi/2 + K_out l^2: continuous at the edge and rising outward.
- Cp, the pipe potential (eq. 15, with + where the text prints a minus): the integral of the squared
  horizontal distance of every active module to the pipe axis, sum_i (x_i - qx)^2 + (y_i - qy)^2.
- Ct: the integral of sum_j (tau_j / tau_limit)^2 over the active joints (quasi-static gravity).
- With a pipe, its wall: frames at the mouth's height or above stay out of it (in the bore or
  outside the pipe); inside, the head keeps the pipe clearance from the bore's edge (the arm sags
  and lags its plan under load: room for that on the way in; the head is what catches on the lip).
The integrals use the trapezoidal rule on the stage's cost samples.
"""
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from . import collision, spline
from .chain import Chain
from .support import Support


@dataclass
class Weights:
    k1: float = 1.0          # directive
    k2: float = 1.0          # stability
    k3: float = 0.0          # pipe potential
    k_torque: float = 0.0    # optional torque term
    ks_per_m2: float = 1.0e4  # Ks of eq. 13 (l in metres)
    k_out_per_m2: float = 1.0e3   # the rise outside the polygon
    k_ground_per_m2: float = 1.0e4
    k_clearance_per_m2: float = 1.0e5   # self-collision
    self_margin_m: float = 0.0          # capsule clearance kept between non-adjacent modules
    self_push_m: float = 0.003          # ... and pushed this much beyond it
    k_wall_per_m2: float = 1.0e4     # the pipe's wall (0: ignored, the pipe only attracts)
    pipe_clearance_m: float = 0.0    # frames inside the bore keep this from its edge (pipe_wall_overlap)


@dataclass
class Directive:
    """What Cd asks: the highest head (default), a head height, or a head position."""
    height_m: Optional[float] = None
    target_m: Optional[Sequence[float]] = None

    def cost(self, head) -> float:
        return float(self.costs(np.asarray(head, float)[None, :])[0])

    def costs(self, heads) -> np.ndarray:
        """Cd for (B, 3) head positions."""
        if self.target_m is not None:
            return np.linalg.norm(heads - np.asarray(self.target_m, float), axis=1)
        if self.height_m is not None:
            return np.hypot(heads[:, 2] - self.height_m, 1e-3)
        return -heads[:, 2]


@dataclass
class Pipe:
    """A vertical pipe hanging over the floor (paper fig. 6): axis through (x_m, y_m), inner
    radius radius_m, open mouth mouth_m above the floor."""
    x_m: float
    y_m: float
    radius_m: float
    mouth_m: float = 0.25
    wall_m: float = 0.012

    def entry_point(self, depth_m: float = 0.05):
        """A head target on the axis, depth_m inside the mouth."""
        return (self.x_m, self.y_m, self.mouth_m + depth_m)


def stability_cost(l, ks_per_m2: float, k_out_per_m2: float) -> np.ndarray:  # noqa: E741 - the paper's l
    """Cs(t) of eq. 13 for signed distances l (> 0 inside), with the outside branch above."""
    d = np.asarray(l, float)
    inside = np.pi / 2 - np.arctan(ks_per_m2 * d ** 2)
    outside = np.pi / 2 + k_out_per_m2 * d ** 2
    return np.where(d > 0, inside, outside)


def pipe_cost(positions_xy, pipe: Pipe) -> float:
    """The integrand of eq. 15 (a sum of squares) for the given active modules."""
    d = np.asarray(positions_xy, float) - (pipe.x_m, pipe.y_m)
    return float(np.sum(d[:, 0] ** 2 + d[:, 1] ** 2))


def head_clearance(clearance_m: float, frames: int) -> np.ndarray:
    """Per frame, the clearance from the bore's edge: the head's (frame 0) only. Kept by every
    frame, the whole arm would have to enter near the axis, and no tuning seed got in that way."""
    out = np.zeros(frames)
    out[0] = clearance_m
    return out


def pipe_wall_overlap(positions, pipe: Pipe, module_radius_m: float, clearance_m=0.0) -> np.ndarray:
    """How far (m) each frame's capsule reaches into the pipe's wall, which spans radii
    [radius, radius + wall] from the mouth up: frames at or above the mouth (less a module radius)
    stay within the bore, clearance_m from its edge, or outside the pipe; the overlap is the way
    out, inward or outward. clearance_m may be one per frame (head_clearance). The clearance is
    room for the arm's sag: a head planned at the bore's edge caught on the lip in physics."""
    p = np.asarray(positions, float)
    off_axis = np.hypot(p[..., 0] - pipe.x_m, p[..., 1] - pipe.y_m)
    high = p[..., 2] > pipe.mouth_m - module_radius_m
    inward = off_axis - (pipe.radius_m - module_radius_m - clearance_m)
    outward = pipe.radius_m + pipe.wall_m + module_radius_m - off_axis
    return np.where(high, np.clip(np.minimum(inward, outward), 0.0, None), 0.0)


class StageCost:
    """The cost of one stage as a function of the active joints' end offsets delta."""

    def __init__(self, chain: Chain, q_start, active_modules: int, support: Support,
                 weights: Weights, directive: Directive, t_end_s: float, num_samples: int,
                 pipe: Optional[Pipe] = None, torque_limit_nm: float = 1.0):
        self.chain = chain
        self.q_start = np.asarray(q_start, float).copy()
        self.m = int(active_modules)
        self.support = support
        self.w = weights
        self.directive = directive
        self.t_end_s = float(t_end_s)
        self.t_s = np.linspace(0.0, self.t_end_s, int(num_samples))
        self._trapezoid = np.full(len(self.t_s), self.t_s[1] - self.t_s[0])
        self._trapezoid[[0, -1]] *= 0.5
        self.pipe = pipe
        self.torque_limit_nm = float(torque_limit_nm)
        self._pairs = collision.module_pairs(chain.num_modules, moving_below=self.m)
        self.kin = chain.stage_kinematics(self.q_start, self.m)
        start = collision.clearances(self.kin.positions(self.q_start[None, :self.m])[0], chain.radius_m,
                                     self._pairs)
        self._push_to_m = weights.self_margin_m + np.clip(start - weights.self_margin_m, 0.0,
                                                          weights.self_push_m)

    # ---- trajectory ----------------------------------------------------------------------------
    def joints(self, delta, t_s) -> np.ndarray:
        """(len(t), N) joint angles: the active joints on their cubics, the base joints fixed."""
        t = np.atleast_1d(np.asarray(t_s, float))
        q = np.repeat(self.q_start[None, :], len(t), axis=0)
        q[:, :self.m] = spline.positions(self.q_start[:self.m], delta, self.t_end_s, t)
        return q

    def poses(self, delta, t_s):
        return [self.chain.pose(q) for q in self.joints(delta, t_s)]

    def positions_com(self, delta, t_s):
        """((len(t), F, 3) frame positions, (len(t), 3) CoGs) in the world (batched FK)."""
        t = np.atleast_1d(np.asarray(t_s, float))
        return self.kin.positions_com(spline.positions(self.q_start[:self.m], delta, self.t_end_s, t))

    # ---- cost ----------------------------------------------------------------------------------
    def terms(self, delta) -> dict:
        return {k: float(v[0]) for k, v in self.terms_batch(np.asarray(delta, float)[None, :]).items()}

    def terms_batch(self, deltas) -> dict:
        """Every term for each row of deltas (B, m): {name: (B,)}; all B x samples postures in one
        batched FK."""
        deltas = np.atleast_2d(deltas)
        b, s_n = len(deltas), len(self.t_s)
        w, m, r = self.w, self.m, self.chain.radius_m
        t = self.t_s[:, None]
        a, bb = spline.coefficients(deltas, self.t_end_s)              # (B, m) each
        q = a[:, None, :] * t ** 3 + bb[:, None, :] * t ** 2 + self.q_start[:m]   # (B, S, m)
        pos, com = self.kin.positions_com(q.reshape(b * s_n, m))
        pos = pos.reshape(b, s_n, -1, 3)
        zmp = com[:, :2]
        cs = stability_cost(self.support.signed_distance(zmp), w.ks_per_m2, w.k_out_per_m2).reshape(b, s_n)
        out = {"Cd": self.directive.costs(pos[:, -1, 0]), "Cs": self._integrate(cs)}
        if self.pipe is not None:
            d = pos[:, :, :m, :2] - (self.pipe.x_m, self.pipe.y_m)
            out["Cp"] = self._integrate(np.sum(d ** 2, axis=(2, 3)))
            wall = pipe_wall_overlap(pos[:, :, :m], self.pipe, r, head_clearance(w.pipe_clearance_m, m))
            out["pipe_wall"] = self._integrate(np.sum(wall ** 2, axis=2))
        if w.k_torque:
            qq = np.repeat(self.q_start[None, None, :], s_n, axis=1).repeat(b, axis=0)
            qq[:, :, :m] = q
            ratios = [[np.sum((self.chain.gravity_torques(self.chain.pose(x), m) / self.torque_limit_nm) ** 2)
                       for x in row] for row in qq]
            out["Ct"] = self._integrate(np.asarray(ratios))
        out["ground"] = self._integrate(np.sum(np.clip(r - pos[:, :, :m, 2], 0.0, None) ** 2, axis=2))
        short = np.clip(self._push_to_m - collision.clearances(pos, r, self._pairs), 0.0, None)
        out["clearance"] = self._integrate(np.sum(short ** 2, axis=2))
        return out

    def totals(self, deltas) -> np.ndarray:
        """C of eq. 9 (with the penalties) for each row of deltas (B, m)."""
        t = self.terms_batch(deltas)
        w = self.w
        zero = 0.0
        return (w.k1 * t["Cd"] + w.k2 * t["Cs"] + w.k3 * t.get("Cp", zero)
                + w.k_wall_per_m2 * t.get("pipe_wall", zero)
                + w.k_torque * t.get("Ct", zero) + w.k_ground_per_m2 * t["ground"]
                + w.k_clearance_per_m2 * t["clearance"])

    def __call__(self, delta) -> float:
        return float(self.totals(np.asarray(delta, float)[None, :])[0])

    def value_and_gradient(self, delta, step: float, lower, upper):
        """(C, dC/d delta) by forward differences of `step` (backward at an upper bound), every
        perturbed trajectory in the same batch as the nominal one."""
        x = np.asarray(delta, float)
        h = np.where(x + step <= upper, step, -step)
        batch = np.repeat(x[None, :], len(x) + 1, axis=0)
        batch[np.arange(1, len(x) + 1), np.arange(len(x))] += h
        c = self.totals(batch)
        return float(c[0]), (c[1:] - c[0]) / h

    def _integrate(self, values) -> np.ndarray:
        """Trapezoidal integral over the cost samples (last axis)."""
        return np.asarray(values, float) @ self._trapezoid
