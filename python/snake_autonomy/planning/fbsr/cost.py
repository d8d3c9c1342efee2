"""The stage cost C = K1 Cd + K2 Cs + K3 Cp (paper eq. 9), plus the optional torque term the paper
suggests (III.D, last paragraph) and two penalties the paper's robot did not need written down:
no module below the floor, no module through another.

- Cd, the directive (eq. 10-12): -z of the head at t_end; or the target forms: |z - H| for a
  head height H, |p - target| for a head position.
- Cs, stability (eq. 13-14): the integral over the trajectory of pi/2 - atan(Ks l^2) inside the
  polygon, l the ZMP's distance to the nearest edge. Outside, eq. 13 as printed adds l^2 to the
  same expression; its atan part then *falls* with l, which pushes a ZMP just outside further
  out, against the text's intent ("the added l^2 term ... provides a gradient leading back
  inside"). Here outside is pi/2 + K_out l^2: continuous at the edge and rising outward.
- Cp, the pipe potential (eq. 15 with ERRATA #9): the integral of the squared horizontal distance
  of every active module to the pipe axis, sum_i (x_i - qx)^2 + (y_i - qy)^2.
- Ct: the integral of sum_j (tau_j / tau_limit)^2 over the active joints (quasi-static gravity).
- With a pipe, its wall: frames at the mouth's height or above stay out of it (in the bore or
  outside the pipe).
The integrals use the trapezoidal rule on the stage's cost samples.
"""
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from . import spline
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
    k_clearance_per_m2: float = 1.0e3
    k_wall_per_m2: float = 1.0e4     # the pipe's wall (0: ignored, the pipe only attracts)


@dataclass
class Directive:
    """What Cd asks: the highest head (default), a head height, or a head position."""
    height_m: Optional[float] = None
    target_m: Optional[Sequence[float]] = None

    def cost(self, head) -> float:
        if self.target_m is not None:
            return float(np.linalg.norm(head - np.asarray(self.target_m, float)))
        if self.height_m is not None:
            return float(np.hypot(head[2] - self.height_m, 1e-3))
        return float(-head[2])


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


def stability_cost(l, ks_per_m2: float, k_out_per_m2: float) -> np.ndarray:
    """Cs(t) of eq. 13 for signed distances l (> 0 inside), with the outside branch above."""
    l = np.asarray(l, float)
    inside = np.pi / 2 - np.arctan(ks_per_m2 * l ** 2)
    outside = np.pi / 2 + k_out_per_m2 * l ** 2
    return np.where(l > 0, inside, outside)


def pipe_cost(positions_xy, pipe: Pipe) -> float:
    """The integrand of eq. 15 (ERRATA #9: a sum of squares) for the given active modules."""
    d = np.asarray(positions_xy, float) - (pipe.x_m, pipe.y_m)
    return float(np.sum(d[:, 0] ** 2 + d[:, 1] ** 2))


def pipe_wall_overlap(positions, pipe: Pipe, module_radius_m: float) -> np.ndarray:
    """How far (m) each frame's capsule reaches into the pipe's wall, which spans radii
    [radius, radius + wall] from the mouth up: frames at or above the mouth (less a module radius)
    stay within the bore or outside the pipe; the overlap is the way out, inward or outward."""
    p = np.asarray(positions, float)
    off_axis = np.hypot(p[..., 0] - pipe.x_m, p[..., 1] - pipe.y_m)
    high = p[..., 2] > pipe.mouth_m - module_radius_m
    inward = off_axis - (pipe.radius_m - module_radius_m)
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
        n_f = chain.num_frames
        i, j = np.meshgrid(np.arange(n_f), np.arange(n_f), indexing="ij")
        moving = (i < self.m) | (j < self.m)
        self._pairs = np.argwhere((j - i >= 3) & moving)

    # ---- trajectory ----------------------------------------------------------------------------
    def joints(self, delta, t_s) -> np.ndarray:
        """(len(t), N) joint angles: the active joints on their cubics, the base joints fixed."""
        t = np.atleast_1d(np.asarray(t_s, float))
        q = np.repeat(self.q_start[None, :], len(t), axis=0)
        q[:, :self.m] = spline.positions(self.q_start[:self.m], delta, self.t_end_s, t)
        return q

    def poses(self, delta, t_s):
        return [self.chain.pose(q) for q in self.joints(delta, t_s)]

    # ---- cost ----------------------------------------------------------------------------------
    def terms(self, delta) -> dict:
        q = self.joints(delta, self.t_s)
        w, m, r = self.w, self.m, self.chain.radius_m
        pc = [self.chain.positions_com(qq) for qq in q]
        pos = np.array([p for p, _ in pc])                  # (samples, frames, 3)
        zmp = np.array([c[:2] for _, c in pc])
        cs = stability_cost(self.support.signed_distance(zmp), w.ks_per_m2, w.k_out_per_m2)
        out = {"Cd": self.directive.cost(pos[-1, 0]), "Cs": self._integrate(cs)}
        if self.pipe is not None:
            d = pos[:, :m, :2] - (self.pipe.x_m, self.pipe.y_m)
            out["Cp"] = self._integrate(np.sum(d ** 2, axis=(1, 2)))
            wall = pipe_wall_overlap(pos[:, :m], self.pipe, r)
            out["pipe_wall"] = self._integrate(np.sum(wall ** 2, axis=1))
        if w.k_torque:
            ratios = [np.sum((self.chain.gravity_torques(self.chain.pose(qq), m)
                              / self.torque_limit_nm) ** 2) for qq in q]
            out["Ct"] = self._integrate(ratios)
        out["ground"] = self._integrate(np.sum(np.clip(r - pos[:, :m, 2], 0.0, None) ** 2, axis=1))
        a, b = pos[:, self._pairs[:, 0]], pos[:, self._pairs[:, 1]]
        gap = np.clip(2.0 * r - np.linalg.norm(a - b, axis=2), 0.0, None)
        out["clearance"] = self._integrate(np.sum(gap ** 2, axis=1))
        return out

    def __call__(self, delta) -> float:
        t = self.terms(delta)
        w = self.w
        return (w.k1 * t["Cd"] + w.k2 * t["Cs"] + w.k3 * t.get("Cp", 0.0)
                + w.k_wall_per_m2 * t.get("pipe_wall", 0.0)
                + w.k_torque * t.get("Ct", 0.0) + w.k_ground_per_m2 * t["ground"]
                + w.k_clearance_per_m2 * t["clearance"])

    def _integrate(self, values) -> float:
        return float(self._trapezoid @ np.asarray(values, float))
