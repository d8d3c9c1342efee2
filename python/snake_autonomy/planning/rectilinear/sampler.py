"""Trajectory sampling and selection (Chang et al. III): n unicycle arcs from the current pose
(n odd: the straight one plus as many left as right, path curvatures evenly within +-c_max), each
checked in perception space; the longest collision-free prefix wins, then the least curvature.

An arc's free length is its collision-free prefix less margin_m (the head's front beyond base_link
plus a safety distance: the follower runs on past a path's end until the next replan). An arc whose
free length is shorter than min_free_m is not a candidate; when none is, the result
says so (no_free_arc) and the caller stops (planner.py: backs off or turns in place).

Optional goal bias (not in the paper, off by default): arcs whose free length is within
goal_tie_m of the longest count as equally long, and among them the one whose free prefix passes
closest to the goal (to 1 cm) is taken, then the one whose prefix ends closest to it (a goal
behind the robot: every prefix passes closest at its start), before curvature decides; an arc free beyond the goal's
distance counts as long enough (the far floor is often marked unsure at the horizon). Comparing the heading at
the prefix's end instead fails with the goal nearer than the horizon: every prefix ends past it and
the robot drives by the goal. lateral_margin_m widens the checked footprint on each side (the body
slips sideways and bends inside a turn, and its middle can touch an obstacle the head cleared).

known_free_m: only an arc's first known_free_m must be seen free; beyond it only
a point some view shows as not ground ends the free prefix (the paper's rule cut every curved arc
where COBRA's 0.5 m footprint leaves the 55 deg view, so the straight arc always won).
footprint_taper_m: the footprint grows from the head's (start_width_m) to the full width over the
first metres of an arc (a full-width footprint at the start pose overlapped the obstacle beside the
body and blocked every arc, those leaving it too). resume_free_m: after a stop, a longer free prefix
to resume. The arcs are the head's: arcs of the body's middle with the body's sweep checked (with
candidates within a step of the current curvature), an option no shipped config set, were removed.

goal_disc: the goal bias aims at the goal's disc, not its centre: a free prefix that
enters the disc costs 0 (whatever the route says there); among those, the one passing nearest the
centre wins (the robot turns less tightly than the tightest arcs, and one grazing the disc
missed it). A phantom on the disc's edge had sent the route round it, and COBRA circled the goal.
An arc free as far as the goal's centre is long enough, not as far as the disc's edge (that
lets a short arc into a gap narrower than the body).
"""
import math
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np

from .collision_check import PerceptionCollisionChecker, prefix_length
from .unicycle import arc_poses


@dataclass
class SamplerParams:
    """config/nav.yaml `sampler:`; the defaults are its values (COBRA's). The paper's planner: the
    keys marked "off" at 0, false or inf."""
    num_arcs: int = 13
    max_curvature_per_m: float = 3.0      # path curvature c = omega / v (from the gait map's range)
    horizon_m: float = 1.2                # length of each candidate arc
    spacing_m: float = 0.02               # poses along an arc
    min_free_m: float = 0.15              # shorter free prefixes: no candidate
    resume_free_m: float = 0.3            # after a replan with no free arc: candidates need at
                                          # least this (hysteresis: backing off 7 cm and driving
                                          # back into the same gap is no way round); off: 0
    margin_m: float = 0.1                 # taken off every free prefix
    goal_tie_m: float = 0.3               # > 0: the goal bias above; off: 0
    lateral_margin_m: float = 0.08        # added to each side of the head footprint (planner.py)
    body_clearance_m: float = 0.25        # > 0: the footprint's half-width is at least this (the
                                          # body's reach beyond the head's path, planner.py); off: 0
    earlier_views: int = 30               # views of earlier replans kept for hidden points; off: 0
    obstacle_depth_m: float = 0.25        # in those: non-ground this far beyond the ground's edge
                                          # counts as blocked, further is hidden behind it; off: inf
    blocked_wins: bool = True             # a hidden point one earlier view shows as an
                                          # obstacle is blocked, whatever the others show (false:
                                          # ground in any view frees it; collision_check.py)
    footprint_taper_m: float = 0.3        # > 0: the footprint grows from the head's (head width +
                                          # lateral margins, at the start) to the full width over
                                          # this much travel: the body's sweep beyond the head's
                                          # path builds up as it moves; an obstacle beside the body
                                          # now does not block every arc, those leaving it included
    known_free_m: float = 0.35            # an arc's first known_free_m of travel must be seen free;
                                          # beyond, only a point seen blocked ends its free prefix (a
                                          # point no view shows yet is seen before the robot gets
                                          # there); inf: every point must be seen free (the paper)
    swing_guard_m: float = 0.2            # > 0: while following an arc, the body's curvature
                                          # changes only as far as reshaping keeps the body's first
                                          # swing_guard_m (from the head) off obstacles the views
                                          # show (planner.py _swing_bounds); off: 0
    swing_guard_tail_m: float = 0.2       # > 0: the guard also keeps the body's last metres (from
                                          # the tail) off what the obstacle map holds (not the views)
    swing_obstacle_depth_m: float = 0.1   # the swing guard's obstacles: non-ground up to this beyond a
                                          # view's ground edge (the obstacle's face), not obstacle_depth_m
    turn_free_m: float = 0.05             # > 0: a turn in place needs the tightest arc on its
                                          # side free for this much (after margin_m): the gait crawls on
                                          # while it turns (COBRA at kappa 1.5 /m: 4-5 mm/s, so 4-5 cm a
                                          # replan); else it backs off. off: 0
    turn_keeps_side: bool = True          # a turn in place only to the side chosen at the
                                          # stop's first replan (planner._turning); that side not free:
                                          # back off. false: the other side is tried next
    goal_disc: bool = True                # the goal bias aims at the goal's disc (the caller's
                                          # goal_radius_m), not its centre: a free prefix that enters the
                                          # disc reaches the goal (goal_err 0). false: the centre (radius 0)
    blocked_wins_depth_m: float = 0.1     # with blocked_wins, only non-ground within this of an
                                          # earlier view's ground edge (the face) wins over ground another
                                          # view shows; the shadow behind it (to obstacle_depth_m) does not
    back_off_check_m: float = 0.1         # > 0: backing off needs the tail's track continued this
                                          # far backwards clear of what the views and the obstacle map show
                                          # (planner._back_off_clear); else a turn in place. off: 0
    crawl_guard_m: float = 0.2            # > 0: the swing guard also predicts the crawl: the body
                                          # in its new shape moves rigidly with its middle, which goes along
                                          # its own tangent this far turning at the measured rate (none
                                          # within crawl_dead_band_per_m); a curvature that crawls the body
                                          # into what the obstacle map holds is not allowed
                                          # (planner._crawl_bounds). off: 0
    crawl_dead_band_per_m: float = 0.35   # the body turns only beyond this curvature (COBRA: not
                                          # below about 0.35-0.4 /m, test_nav_body_model.py); beyond it, at
                                          # follower omega_per_kappa per 1/m above it
    crawl_margin_m: float = 0.02          # the crawl guard's clearance beyond half the body's width
    reshape_keeps_centroid: bool = True   # the body reshapes about its centroid (measured on COBRA),
                                          # not its middle (body_model.body_poses): the swing guard, the
                                          # crawl guard and the turn in place. false: about the middle
    crawl_blocked_backs_off: bool = True  # when no curvature the swing guard allows crawls clear
                                          # (crawl guard on), back off along the track if its tail's track is
                                          # clear; false: follow within the swing guard's bounds
    swing_guard_body: bool = True         # the swing guard also keeps the stations between its front
                                          # and its tail off the obstacle map: none may come nearer the map's
                                          # obstacles than half the body's width + crawl_margin_m, or than
                                          # it already is when it is nearer (planner._swing_bounds)
    crawl_forces_toward_arc: bool = True  # the current kappa's crawl failing forces the nearest passing
                                          # kappa on the chosen arc's side of it (towards its feed-forward
                                          # kappa) when one passes there; else back off. false: back off
                                          # whenever the current one fails

    def validate(self) -> List[str]:
        """Every key's range (config.py checks the types where a file is loaded)."""
        p = []
        if not isinstance(self.num_arcs, int) or self.num_arcs < 1 or self.num_arcs % 2 == 0:
            p.append(f"num_arcs: must be an odd integer >= 1, got {self.num_arcs!r}")
        if not isinstance(self.earlier_views, int) or self.earlier_views < 0:
            p.append(f"earlier_views: must be an integer >= 0, got {self.earlier_views!r}")
        for key in ("max_curvature_per_m", "horizon_m", "spacing_m", "swing_obstacle_depth_m"):
            if not getattr(self, key) > 0:
                p.append(f"{key}: must be > 0, got {getattr(self, key)}")
        for key in ("min_free_m", "resume_free_m", "margin_m", "goal_tie_m", "lateral_margin_m", "body_clearance_m",
                    "obstacle_depth_m", "footprint_taper_m", "known_free_m", "swing_guard_m", "swing_guard_tail_m",
                    "turn_free_m", "blocked_wins_depth_m", "back_off_check_m", "crawl_guard_m",
                    "crawl_dead_band_per_m", "crawl_margin_m"):
            if not getattr(self, key) >= 0:
                p.append(f"{key}: must be >= 0, got {getattr(self, key)}")
        for key in ("blocked_wins", "turn_keeps_side", "goal_disc", "reshape_keeps_centroid",
                    "swing_guard_body", "crawl_blocked_backs_off", "crawl_forces_toward_arc"):
            if not isinstance(getattr(self, key), bool):
                p.append(f"{key}: must be true or false, got {getattr(self, key)!r}")
        return p


def candidate_arcs(p: SamplerParams) -> List[Tuple[float, np.ndarray, np.ndarray]]:
    """The head's candidate arcs of the sampler section: (path curvature, (N, 3) poses from the origin
    heading +x, (N,) arc lengths); num_arcs curvatures evenly within +-max_curvature_per_m (one:
    straight)."""
    curvatures = (np.linspace(-p.max_curvature_per_m, p.max_curvature_per_m, p.num_arcs)
                  if p.num_arcs // 2 else np.zeros(1))
    arcs = []
    for c in curvatures:
        poses = arc_poses(float(c), p.horizon_m, p.spacing_m)
        arcs.append((float(c), poses, np.linspace(0.0, p.horizon_m, len(poses))))
    return arcs


@dataclass
class Arc:
    curvature_per_m: float
    poses: np.ndarray          # (N, 3) the head's path in the ground frame of the planning pose
    s_m: np.ndarray            # (N,) arc length of each pose
    free_m: float = 0.0        # collision-free prefix
    limit: str = ""            # what ends it (layered planner): obstacle, unseen (the head leaves the floor
                               # the views showed), body (the body sweep); "" the horizon or not told


@dataclass
class Selection:
    arcs: List[Arc] = field(default_factory=list)
    chosen: Optional[int] = None          # index into arcs; None: no free arc

    @property
    def no_free_arc(self) -> bool:
        return self.chosen is None

    @property
    def arc(self) -> Optional[Arc]:
        return None if self.chosen is None else self.arcs[self.chosen]


class TrajectorySampler:
    def __init__(self, checker: PerceptionCollisionChecker, params: Optional[SamplerParams] = None,
                 start_width_m: Optional[float] = None):
        """start_width_m: the footprint's width at an arc's start (footprint_taper_m)."""
        self.checker = checker
        self.start_width_m = start_width_m
        self.params = params or SamplerParams()
        problems = self.params.validate()
        if problems:
            raise ValueError("sampler: " + "; ".join(problems))
        p = self.params
        self._arcs = candidate_arcs(p)
        self.curvatures = np.array([c for c, _, _ in self._arcs])
        self._all = np.vstack([a[1] for a in self._arcs])
        self._all_s = np.concatenate([a[2] for a in self._arcs])
        self._splits = np.cumsum([len(a[1]) for a in self._arcs])[:-1]

    def select(self, ground: np.ndarray, goal_in_ground: Optional[Tuple[float, float]] = None,
               resuming: bool = False, cost_to_go=None, goal_radius_m: float = 0.0) -> Selection:
        """Check every arc against the traversability image `ground` (True = ground) and choose.
        resuming: the last replan found no free arc (candidates need resume_free_m). cost_to_go: None, or a
        callable (M, 2) ground-frame points -> (M,) the route's cost to the goal (route.py): the goal
        bias then takes the arc whose free prefix reaches the least cost, not the least distance.
        goal_radius_m: the goal's radius; with params.goal_disc the goal is that disc (points in it
        cost 0), else its centre."""
        p = self.params
        goal_radius_m = goal_radius_m if p.goal_disc else 0.0
        arcs = self._head_arcs(ground)
        need = max(p.min_free_m, p.resume_free_m) if resuming else p.min_free_m
        cands = [i for i, a in enumerate(arcs) if a.free_m >= need and a.free_m > 0]
        if not cands:
            return Selection(arcs, None)
        longest = max(arcs[i].free_m for i in cands)
        tie = max(p.goal_tie_m, 0.5 * p.spacing_m)
        enough = longest - tie
        if goal_in_ground is not None and p.goal_tie_m > 0:
            # an arc free as far as the goal is long enough (the far floor is often unsure); as far as
            # the goal's centre, not its disc's edge, even with goal_disc (the disc's edge
            # lets a short arc into a gap narrower than the body)
            enough = min(enough, math.hypot(goal_in_ground[0], goal_in_ground[1]))
        best = [i for i in cands if arcs[i].free_m >= enough]

        def key(i):
            a = arcs[i]
            goal_err = depth_err = end_err = 0.0
            if goal_in_ground is not None and p.goal_tie_m > 0:
                n = np.searchsorted(a.s_m, a.free_m, side="right")
                prefix = a.poses[:max(1, n), :2]
                dist = np.hypot(prefix[:, 0] - goal_in_ground[0], prefix[:, 1] - goal_in_ground[1])
                d = dist if cost_to_go is None else np.asarray(cost_to_go(prefix), float)
                if goal_radius_m > 0 and np.min(dist) <= goal_radius_m:
                    # in the goal's disc: there. Among the arcs that enter it, the one passing nearest
                    # the centre: the robot turns less tightly than the tightest arcs, and an arc
                    # grazing the disc on paper misses it
                    d = np.where(dist <= goal_radius_m, 0.0, d)
                    depth_err = float(np.min(dist))
                goal_err, end_err = float(np.min(d)), float(d[-1])
            return (round(goal_err, 2), round(depth_err, 2), round(end_err, 2), abs(a.curvature_per_m))
        return Selection(arcs, min(best, key=key))

    def _head_arcs(self, ground) -> List[Arc]:
        p = self.params
        free_all = self._free(self._all, self._all_s, ground)
        return [Arc(c, poses, s, max(0.0, prefix_length(free, s) - p.margin_m))
                for (c, poses, s), free in zip(self._arcs, np.split(free_all, self._splits))]

    def _free(self, poses: np.ndarray, s_m: np.ndarray, ground) -> np.ndarray:
        """(N,) bool per pose: not blocked, and known (or near field) where s_m < known_free_m."""
        scale = None
        if self.params.footprint_taper_m > 0 and self.start_width_m is not None:
            start = self.checker.width_scale(self.start_width_m)
            scale = start + (1.0 - start) * np.clip(s_m / self.params.footprint_taper_m, 0.0, 1.0)
        blocked, unknown = self.checker.pose_state(poses, ground, scale)
        return ~blocked & ~(unknown & (s_m < self.params.known_free_m))
