"""Receding-horizon following of the chosen arc (Chang et al. IV).

Between replans the follower tracks the planned path (world-frame poses): the target is the
furthest path point within lookahead_m (delta = 60 mm in the paper) of the current pose; the turn
rate is omega = omega_ff + omega_fb, omega_ff = v c (the arc's path curvature c) and omega_fb =
k_heading * (bearing to the target - heading); omega becomes the body curvature kappa through the
inverse of the gait map's linear fit omega(kappa) = omega_per_kappa * kappa + omega_offset, clipped
to the gait's range. Without a fresh pose estimate the pose is predicted with the unicycle model
from the last command.

The commanded kappa is rate-limited (kappa_rate_per_m_s, from the last command's time): the paper's
robot changes its curvature slowly; a kappa that jumps whips the body and rolls the round-linked
simulated COBRA onto its side (bench/nav_roll). The unicycle prediction uses the limited kappa.

The planner may bound the body curvature while a path is followed (set_path kappa_bounds: its swing
guard, planner.py): the commanded kappa is clipped to the bounds before the rate limit.

No free arc: the follower stops forward motion and turns in place (mode TURN_IN_PLACE, towards
`turn_direction`), or with `back_off` it backs off tail first (mode BACK_OFF: the caller runs the
gait backwards) with the body's curvature held, so the body retraces its own track, which it has
just crawled over (turning with kappa_turn_per_m crawls on forward at 5 mm/s on
a tight curve and swings the head (L^2/8) kappa = 0.42 m into what stopped it). Either way the
command's reason says so.
"""
import math
from dataclasses import dataclass
from typing import List, Optional, Tuple

import numpy as np

from .unicycle import predict, wrap

FOLLOW, TURN_IN_PLACE, BACK_OFF, IDLE = "follow", "turn_in_place", "back_off", "idle"
MODES = (FOLLOW, TURN_IN_PLACE, BACK_OFF, IDLE)


@dataclass
class FollowerParams:
    """Defaults: COBRA's (config/nav.yaml follower:, from the gait map of its rectilinear gait)."""
    speed_m_s: float = 0.006354748980833362   # the gait's forward speed (gait map)
    omega_per_kappa: float = 0.00923      # d omega / d kappa (rad/s per 1/m), gait map fit
    omega_offset_rad_s: float = 0.0       # omega at kappa = 0 (drift), gait map fit
    kappa_max_per_m: float = 2.0          # body curvature range of the gait
    lookahead_m: float = 0.15             # the paper's delta is 60 mm; the head sways ~2 cm a gait cycle
    k_heading: float = 0.016              # omega_fb per rad of heading error to the target (1/s)
    turn_in_place_rad_s: float = 0.019    # turn rate the unicycle prediction assumes when turning
    kappa_turn_per_m: float = 1.5         # curvature commanded to turn in place (the gait's forward
                                          # speed is near zero there: bench/nav_gait)
    kappa_rate_per_m_s: float = 0.1       # > 0: the commanded kappa changes at most this fast
                                          # (1/m per s; slow body reshaping keeps the robot upright:
                                          # bench/nav_roll); 0: no limit
    back_off: bool = True                 # no free arc: back off along the track (else turn in place)
    back_off_replans: int = 2             # > 0: back off for this many replans in a row, then turn
                                          # in place with the room gained; 0: back off while no arc is free
    goal_margin_m: float = 0.02           # the loop stops this far inside a goal's disc: the stop moves
                                          # base_link up to 11 mm (bench/nav_stop_shift, both robots)

    def validate(self) -> List[str]:
        p = []
        for key in ("speed_m_s", "kappa_max_per_m", "lookahead_m", "turn_in_place_rad_s",
                    "kappa_turn_per_m"):
            if not getattr(self, key) > 0:
                p.append(f"{key}: must be > 0, got {getattr(self, key)}")
        if self.omega_per_kappa == 0 or not math.isfinite(self.omega_per_kappa):
            p.append(f"omega_per_kappa: must be finite and non-zero, got {self.omega_per_kappa}")
        if self.k_heading < 0:
            p.append(f"k_heading: must be >= 0, got {self.k_heading}")
        if not isinstance(self.back_off_replans, int) or self.back_off_replans < 0:
            p.append(f"back_off_replans: must be an integer >= 0, got {self.back_off_replans!r}")
        if not (math.isfinite(self.goal_margin_m) and self.goal_margin_m >= 0):
            p.append(f"goal_margin_m: must be a finite number >= 0, got {self.goal_margin_m}")
        if not self.kappa_rate_per_m_s >= 0:
            p.append(f"kappa_rate_per_m_s: must be >= 0, got {self.kappa_rate_per_m_s}")
        return p

    @property
    def min_radius_m(self) -> float:
        """The tightest circle the follower drives: speed / |omega(kappa_max)| (drift aside)."""
        return self.speed_m_s / abs(self.omega_per_kappa * self.kappa_max_per_m)

    def kappa(self, omega_rad_s: float) -> float:
        """The inverse gait map, clipped to the gait's range."""
        k = (omega_rad_s - self.omega_offset_rad_s) / self.omega_per_kappa
        return max(-self.kappa_max_per_m, min(self.kappa_max_per_m, k))

    def omega(self, kappa_per_m: float) -> float:
        return self.omega_per_kappa * kappa_per_m + self.omega_offset_rad_s


@dataclass
class Command:
    mode: str
    kappa_per_m: float = 0.0
    omega_ff_rad_s: float = 0.0
    omega_fb_rad_s: float = 0.0
    target: Optional[tuple] = None
    reason: str = ""


class RecedingHorizonFollower:
    def __init__(self, params: Optional[FollowerParams] = None):
        self.params = params or FollowerParams()
        problems = self.params.validate()
        if problems:
            raise ValueError("follower: " + "; ".join(problems))
        self.path: Optional[np.ndarray] = None
        self.path_curvature = 0.0
        self.mode = IDLE
        self.turn_direction = 1.0
        self._turn_kappa = self.params.kappa_turn_per_m
        self.pose = None
        self._t = None
        self._omega = 0.0
        self._v = 0.0
        self._kappa = 0.0
        self._bounds = None
        self._back_kappa: Optional[float] = None

    @property
    def kappa_per_m(self) -> float:
        """The last commanded (rate-limited) body curvature."""
        return self._kappa

    def recovery_kappa(self) -> Optional[float]:
        """The curvature the running recovery steers towards (signed; backing off with the body's
        curvature held: the last commanded one); None when no recovery runs."""
        if self.mode == TURN_IN_PLACE:
            return self.turn_direction * self._turn_kappa
        if self.mode == BACK_OFF:
            return self._kappa if self._back_kappa is None else self._back_kappa
        return None

    def set_path(self, path_world: np.ndarray, curvature_per_m: float,
                 kappa_bounds: Optional[Tuple[float, float]] = None) -> None:
        """kappa_bounds: (lo, hi) body curvature while following this path (the planner's swing
        guard); None: the gait's range."""
        if kappa_bounds is not None and not kappa_bounds[0] <= kappa_bounds[1]:
            raise ValueError(f"kappa_bounds: expected lo <= hi, got {kappa_bounds!r}")
        self.path = np.asarray(path_world, float)
        self.path_curvature = float(curvature_per_m)
        self.mode = FOLLOW
        self._bounds = None if kappa_bounds is None else (float(kappa_bounds[0]), float(kappa_bounds[1]))

    def stop_and_turn(self, direction: float, kappa_per_m: Optional[float] = None) -> None:
        """No free arc: turn in place towards direction (+1 left / CCW, -1 right) with kappa_per_m
        (default kappa_turn_per_m)."""
        self.path = None
        self.mode = TURN_IN_PLACE
        self.turn_direction = 1.0 if direction >= 0 else -1.0
        self._turn_kappa = self.params.kappa_turn_per_m if kappa_per_m is None else abs(float(kappa_per_m))

    def back_off_now(self, kappa_per_m: Optional[float] = None) -> None:
        """No free arc: back off tail first with kappa_per_m (reached at the rate limit), or the body's
        curvature held (its own track)."""
        self.path = None
        self.mode = BACK_OFF
        self._back_kappa = None if kappa_per_m is None else float(kappa_per_m)

    def update(self, t_s: float, pose=None) -> Command:
        """pose: a fresh (x, y, theta) estimate, or None to predict from the last command."""
        elapsed = t_s - self._t if self._t is not None else None
        if pose is not None:
            self.pose = tuple(pose)
        elif self.pose is not None and elapsed is not None:
            self.pose = predict(self.pose, self._v, self._omega, elapsed)
        self._t = t_s
        p = self.params
        if self.mode == TURN_IN_PLACE:
            frac = self._turn_kappa / p.kappa_turn_per_m
            self._v, self._omega = 0.0, self.turn_direction * p.turn_in_place_rad_s * frac
            side = "left" if self.turn_direction > 0 else "right"
            return Command(TURN_IN_PLACE, self._limit(self.recovery_kappa(), elapsed),
                           reason=f"no collision-free arc: stopped, turning in place {side}")
        if self.mode == BACK_OFF:
            kappa = self._limit(self.recovery_kappa(), elapsed)
            self._v, self._omega = -p.speed_m_s, -p.omega(kappa)
            return Command(BACK_OFF, kappa,
                           reason="no collision-free arc: backing off along the track")
        if self.mode != FOLLOW or self.path is None or self.pose is None:
            self._v, self._omega = 0.0, 0.0
            return Command(IDLE, self._limit(0.0, elapsed), reason="no path")
        target = self.target(self.pose)
        omega_ff = p.speed_m_s * self.path_curvature
        x, y, th = self.pose
        bearing = math.atan2(target[1] - y, target[0] - x)
        dist = math.hypot(target[0] - x, target[1] - y)
        at_end = math.hypot(self.path[-1, 0] - x, self.path[-1, 1] - y) <= p.lookahead_m
        # past the path's end (until the next replan): feedforward only, never turn back to it
        omega_fb = p.k_heading * wrap(bearing - th) if dist > 1e-3 and not at_end else 0.0
        kappa = p.kappa(omega_ff + omega_fb)
        if self._bounds is not None:
            kappa = min(self._bounds[1], max(self._bounds[0], kappa))
        kappa = self._limit(kappa, elapsed)
        self._v, self._omega = p.speed_m_s, p.omega(kappa)
        return Command(FOLLOW, kappa, omega_ff, omega_fb, tuple(target))

    def _limit(self, kappa: float, elapsed) -> float:
        """kappa moved from the last command's at most kappa_rate_per_m_s * elapsed."""
        rate = self.params.kappa_rate_per_m_s
        if rate > 0:
            step = rate * max(0.0, elapsed) if elapsed is not None else 0.0
            kappa = self._kappa + max(-step, min(step, kappa - self._kappa))
        self._kappa = kappa
        return kappa

    def target(self, pose) -> np.ndarray:
        """The furthest path point (in path order) within lookahead_m of pose; if none is, the
        path point nearest to the pose."""
        d = np.hypot(self.path[:, 0] - pose[0], self.path[:, 1] - pose[1])
        within = np.nonzero(d <= self.params.lookahead_m)[0]
        i = int(within.max()) if len(within) else int(np.argmin(d))
        return self.path[i, :2]
