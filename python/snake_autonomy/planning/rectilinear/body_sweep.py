"""The body sweep: the one validity check of the layered planner, ROS-free.

A candidate motion of the rectilinear robot is a body curvature kappa held until the next replan.
What the whole body sweeps doing it (body_model.py, measured on COBRA with the gait map,
test/python/test_nav_body_model.py):
1. the body reshapes from the current kappa to the new one about its centroid (COBRA) or its middle
   (`reshape_keeps_centroid`): both ends swing (L^2/8) dkappa to the inside of the bend;
2. then it crawls: the body in its new shape is carried rigidly with its middle along the middle's
   tangent, turning at the gait map's omega(kappa) (none within `dead_band_per_m`: below it the
   measured body translates, it does not turn), forwards or (backing off, the reverse gait)
   backwards.
With `reshape_while_crawling` the two overlap as the robot moves: the follower reaches the new
curvature at its rate limit while the gait crawls on, so each reshape shape is checked where the
crawl has carried it by then (bench/nav_body_model_error: closer to the plant's body at the next
replan; not the default, docs/navigation_measured.md).
The sweep is every station of the body (every `station_m` from tail to head) in each reshape shape and
at every `step_m` of the crawl. A sweep is clear up to the travel where a station first comes nearer
an occupied cell of the local map than half the body's width + `margin_m` -- or, when the body already
lies nearer than that (beside an obstacle), more than SLACK_M nearer than its nearest station is now:
it may move along the obstacle or away. With the robot's joint chain (body_chain.py, what the
navigation loop runs) the body now is where its measured joint angles put it, and the reshape moves
the yaw joints linearly to the biases the driver commands for the new curvature (the pitch joints'
wave kept), each shape by the forward kinematics; without joints, from the biases of the curvature
commanded. Without a chain the shapes are uniform arcs through base_link (body_model.py), 5-10 cm off
the body at its tail for the 12-link robot (bench/nav_body_model_error). A modelled station can still
overlap an obstacle the real body is clear of (the pose's error, the map's): the occupied cells under
the modelled body now do not count for this body (LocalMap.distance_clearing).
A reshape that is not clear makes the whole motion invalid (free travel 0).
One model for every motion the planner asks about: the candidate arcs, the follower's curvature
bounds, backing off and turning in place (recovery.py).
"""
from dataclasses import dataclass
from typing import List, Optional, Tuple

import numpy as np

from .body_chain import BodyChain, BodyState
from .body_model import RESHAPE_FRACTIONS, BodyGeometry, middle_pose
from .unicycle import arc_poses, predict

SLACK_M = 0.02              # the body may come this much nearer than it is now (half a station spacing)


@dataclass(frozen=True)
class SweepParams:
    """config/nav.yaml `body_sweep:`; the defaults are its values (COBRA's)."""
    margin_m: float = 0.05                # clearance beyond half the body's width
    station_m: float = 0.04               # body stations, tail to head
    step_m: float = 0.05                  # crawl samples
    reshape_keeps_centroid: bool = True   # COBRA's measured body; the 12-link robot's: about the middle
    dead_band_per_m: float = 0.35         # the body does not turn below this curvature (COBRA)
    reshape_while_crawling: bool = False  # the reshape at the follower's rate limit while the gait crawls on

    def validate(self) -> List[str]:
        p = [f"{k}: must be > 0, got {getattr(self, k)}" for k in ("station_m", "step_m") if not getattr(self, k) > 0]
        p += [f"{k}: must be >= 0, got {getattr(self, k)}" for k in ("margin_m", "dead_band_per_m")
              if not getattr(self, k) >= 0]
        p += [f"{k}: must be true or false, got {getattr(self, k)!r}"
              for k in ("reshape_keeps_centroid", "reshape_while_crawling") if not isinstance(getattr(self, k), bool)]
        return p


@dataclass
class Sweep:
    rows: np.ndarray         # (R, N, 2) stations in the ground frame: row 0 the body now, then the reshape, the crawl
    travel_m: np.ndarray     # (R,) the crawl's travel at each row (the reshape's rows: 0, or where it has crawled to)
    reshape_rows: int        # rows 1..reshape_rows are the reshape


@dataclass
class SweepCheck:
    free_m: float            # travel before the first station that is not clear (-1: the reshape is not)
    clearance_m: float       # the least distance to an obstacle beyond half the width, up to free_m


class BodySweep:
    def __init__(self, geometry: BodyGeometry, follower_params, params: SweepParams = SweepParams(),
                 chain: Optional[BodyChain] = None):
        """chain: the robot's joint chain (body_chain.py): the shapes from joint angles; None: uniform arcs."""
        self.geometry, self.fp, self.params, self.chain = geometry, follower_params, params, chain
        self.need_m = 0.5 * geometry.width_m + params.margin_m
        # the stations' arc lengths from the middle, tail to head (as body_model.body_poses places them)
        h, n = geometry.half_length_m, max(1, int(np.ceil(geometry.half_length_m / params.station_m)))
        self._s = np.concatenate([np.linspace(-h, 0.0, n + 1), np.linspace(0.0, h, n + 1)[1:]])
        self._from_base = h - self._s      # the same stations' arc lengths from base_link (the chain's)

    @property
    def stations_from_base(self) -> np.ndarray:
        """The stations' arc lengths from base_link (m), tail to head: the rows of every shape."""
        return self._from_base

    def turn_rate(self, kappa: float) -> float:
        """The body's turn rate at kappa (rad/s): the gait map's omega beyond the dead band."""
        k = np.sign(kappa) * max(0.0, abs(kappa) - self.params.dead_band_per_m)
        return self.fp.omega(float(k))

    def body_now(self, kappa_now: float, body: Optional[BodyState] = None) -> np.ndarray:
        """(N, 2) the body's stations now (base_link at the ground frame's origin, heading 0): a sweep's
        row 0, without its reshape and crawl."""
        return self._shapes(kappa_now, kappa_now, body, (0.0,))[0][0]

    def _shapes(self, kappa_now: float, kappa_new: float, body: Optional[BodyState], fractions):
        """((K, N, 2) the body in each shape from now (fraction 0) to kappa_new (fraction 1), the last
        shape's middle pose (x, y, heading)). With a chain: the joints' angles (body, or without it the
        biases of kappa_now) moved linearly to kappa_new's biases, each shape by the forward kinematics,
        placed so that its middle keeps the first's heading and its middle (or centroid) the first's
        place. Without: uniform arcs through base_link (body_model.py)."""
        g, p = self.geometry, self.params
        f = np.asarray(fractions, float)
        if self.chain is None:
            middle = middle_pose((0.0, 0.0, 0.0), kappa_now, g.half_length_m)
            shapes = _uniform_shapes(middle, kappa_now + f * (kappa_new - kappa_now), self._s, p.reshape_keeps_centroid)
            return shapes[:, :, :2], tuple(shapes[-1][len(self._s) // 2])
        if body is None:
            q0, R = self.chain.bent(np.zeros(self.chain.num_joints), kappa_now), np.eye(3)
        else:
            q0, R = np.asarray(body.q, float), np.asarray(body.T_ground_base, float)[:3, :3]
        q1 = self.chain.bent(q0, kappa_new)
        shapes = self.chain.stations(q0[None, :] + f[:, None] * (q1 - q0)[None, :], R, self._from_base)
        m = len(self._s) // 2
        heading = np.arctan2(*(shapes[:, m + 1] - shapes[:, m - 1])[:, ::-1].T)
        turn = heading[0] - heading
        c, sn = np.cos(turn)[:, None], np.sin(turn)[:, None]
        d = shapes - shapes[:, m:m + 1]
        shapes = shapes[0, m] + np.stack([c * d[..., 0] - sn * d[..., 1], sn * d[..., 0] + c * d[..., 1]], axis=-1)
        if p.reshape_keeps_centroid:
            shapes += shapes[0:1].mean(axis=1, keepdims=True) - shapes.mean(axis=1, keepdims=True)
        return shapes, (*shapes[-1, m], float(heading[0]))

    def sweep(self, kappa_now: float, kappa_new: float, travel_m: float, body: Optional[BodyState] = None) -> Sweep:
        """The body's stations from its shape now (base_link at the ground frame's origin, heading 0)
        through the reshape to kappa_new and travel_m of crawl (negative: backwards). body: the joints'
        angles now (with a chain; None: the shape of kappa_now). With reshape_while_crawling the body
        crawls on while it reshapes (the follower's curvature reaches kappa_new at kappa_rate_per_m_s,
        the gait keeps its speed: DWB's trajectory generator ramping to a velocity at its acceleration
        limit): each reshape shape is where the crawl has carried it by then, turning at the curvature
        of the moment; the crawl after it holds kappa_new. A travel shorter than the reshape's ends
        in the shape reached by then."""
        p = self.params
        sign = -1.0 if travel_m < 0 else 1.0
        reach = abs(travel_m)
        rate = self.fp.kappa_rate_per_m_s
        reshape_m = (self.fp.speed_m_s * abs(kappa_new - kappa_now) / rate
                     if p.reshape_while_crawling and rate > 0 and reach > 0 else 0.0)
        # a motion shorter than the reshape ends part of the way to kappa_new (the next replan goes on)
        part = min(1.0, reach / reshape_m) if reshape_m > 0 else 1.0
        fractions = part * np.array([0.0, *RESHAPE_FRACTIONS])
        kappa_end = kappa_now + part * (kappa_new - kappa_now)
        shapes, mid = self._shapes(kappa_now, kappa_new, body, fractions)     # (4, N, 2)
        middles = shapes[:, len(self._s) // 2]                                # each shape's middle
        h0 = mid[2]
        at = fractions * reshape_m                                          # travel at each reshape shape
        done = at[-1]
        # the middle's path (start frame: the first middle, heading h0): each reshape segment at its mean
        # curvature, then the crawl at the curvature reached
        ks = kappa_now + 0.5 * (fractions[:-1] + fractions[1:]) * (kappa_new - kappa_now)
        poses = [(0.0, 0.0, 0.0)]
        for k, a, b in zip(ks, at[:-1], at[1:]):
            poses.append(predict(poses[-1], sign, sign * self.turn_rate(k) / self.fp.speed_m_s, b - a))
        path = np.array(poses)
        travel = at
        if reach > done + 1e-9:
            crawl = arc_poses(self.turn_rate(kappa_end) / self.fp.speed_m_s, sign * (reach - done), p.step_m,
                              start=poses[-1])[1:]
            path = np.vstack([path, crawl])
            travel = np.concatenate([at, np.linspace(done, reach, len(crawl) + 1)[1:]])
        n = len(path) - len(at)
        which = np.concatenate([np.arange(len(fractions)), np.full(n, len(fractions) - 1)])
        c0, s0 = np.cos(h0), np.sin(h0)
        d = shapes - middles[:, None, :]                                   # each shape about its middle, once
        rel = np.stack([c0 * d[..., 0] + s0 * d[..., 1], -s0 * d[..., 0] + c0 * d[..., 1]], axis=-1)[which]
        heading = h0 + path[:, 2]
        ox = middles[which, 0] + c0 * path[:, 0] - s0 * path[:, 1]
        oy = middles[which, 1] + s0 * path[:, 0] + c0 * path[:, 1]
        c, sn = np.cos(heading)[:, None], np.sin(heading)[:, None]
        rows = np.stack([ox[:, None] + c * rel[..., 0] - sn * rel[..., 1],
                         oy[:, None] + sn * rel[..., 0] + c * rel[..., 1]], axis=-1)
        return Sweep(rows, travel, len(RESHAPE_FRACTIONS))

    def check(self, sweep: Sweep, local_map, T_world_g: np.ndarray, known: bool = False) -> SweepCheck:
        """How far the sweep is clear of the map's occupied cells (T_world_g: the ground frame in the
        world, 4x4). known: the body must also stay on cells the map knows (seen or lain on): no station
        comes nearer an unknown cell than half the width, or than SLACK_M nearer than the body is now,
        and none that lies on a known cell enters an unknown one."""
        R, N, _ = sweep.rows.shape
        pts = sweep.rows.reshape(-1, 2) @ T_world_g[:2, :2].T + T_world_g[:2, 3]
        d = local_map.distance(pts).reshape(R, N)
        half = 0.5 * self.geometry.width_m
        overlaps = d[0] < half                  # the body cannot lie in an obstacle: the model's or the map's error
        if overlaps.any():
            d = local_map.distance_clearing(pts, pts[:N][overlaps], half + SLACK_M).reshape(R, N)
        nearest = float(d[0].min()) if N else self.need_m
        allowed = min(self.need_m, nearest - SLACK_M)
        ok = (d >= allowed).all(axis=1)
        if known:
            du = local_map.unknown_distance(pts).reshape(R, N)
            half_u = min(half, float(du[0].min()) - SLACK_M) if N else half
            # and no station on a known cell now enters an unknown one (du 0: inside an unknown cell): the
            # allowance above is void when the body already lies beside unknown cells, as the 12-link robot's
            # 5 cm body on 4 cm cells always does (backing off, its tail swung into blocks nobody saw)
            ok &= (du >= half_u).all(axis=1) & ((du > 0) | (du[0] <= 0)[None, :]).all(axis=1)
        margin = (d - 0.5 * self.geometry.width_m).min(axis=1)
        if not ok[:sweep.reshape_rows + 1].all():
            return SweepCheck(-1.0, float(margin[:sweep.reshape_rows + 1].min()))
        bad = np.nonzero(~ok)[0]
        last = R - 1 if not len(bad) else int(bad[0]) - 1
        return SweepCheck(float(sweep.travel_m[last]), float(margin[:last + 1].min()))


def sweep_bounds(kappas: np.ndarray, clear: np.ndarray, chosen: int) -> Tuple[float, float]:
    """The contiguous run of clear candidate curvatures around the chosen one: the follower's bounds."""
    a = b = chosen
    while a > 0 and clear[a - 1]:
        a -= 1
    while b < len(kappas) - 1 and clear[b + 1]:
        b += 1
    return float(kappas[a]), float(kappas[b])


def _uniform_shapes(middle, ks: np.ndarray, s: np.ndarray, keep_centroid: bool) -> np.ndarray:
    """(len(ks), N, 3) the body as uniform arcs of each curvature in ks through `middle` (its pose), the
    stations at arc lengths s from it; keep_centroid: each moved so that its centroid is the first's
    (body_model.body_poses, vectorised: the sweep asks for 4 shapes of 13 candidates every replan)."""
    k = np.asarray(ks, float)[:, None]
    ks_ = k * s[None, :]
    small = np.abs(k) < 1e-9
    kk = np.where(small, 1.0, k)
    x = np.where(small, s[None, :], np.sin(ks_) / kk)
    y = np.where(small, 0.0, (1.0 - np.cos(ks_)) / kk)
    x0, y0, t0 = middle
    c, sn = np.cos(t0), np.sin(t0)
    out = np.stack([x0 + c * x - sn * y, y0 + sn * x + c * y, t0 + ks_], axis=-1)
    if keep_centroid:
        centre = out[:, :, :2].mean(axis=1, keepdims=True)
        out[:, :, :2] += centre[0:1] - centre
    return out
