"""One replan of the perception-space planner (Chang et al. III-IV), ROS-free: a traversability
image, the camera's pose in the ground frame and the robot's pose -> the chosen arc as a world path,
handed to the receding-horizon follower (or stop and turn in place when no arc is free).

No free arc: with follower.back_off the robot first backs off tail first along its own
track for back_off_replans replans (the reverse gait; the body retraces ground it has crawled
over), then turns in place with a turn whose reshaping sweep (body_model.body_poses: both ends swing
(L^2/8) kappa to the inside) the current and earlier images show free, the turning side first,
kappa_turn_per_m then half of it; with no such turn it backs off again. sampler.turn_free_m:
the gait crawls on while the body turns, so a turn also needs the tightest arc on its side free for
turn_free_m. A replan after a stop needs sampler.resume_free_m of free arc to go on.
sampler.turn_keeps_side: the turn keeps the side the stop chose first; when that side cannot be
swept the robot backs off rather than turn the other way (turns to alternate sides swung the head
both ways beside a cylinder). sampler.back_off_check_m: backing off needs the tail's
track clear (_back_off_clear: the views and the obstacle map); when it is not, the robot turns in
place instead (the turning side, then either side), and says why.

Swing guard (sampler.swing_guard_m): following an arc, the follower bends the body only
within curvature bounds this replan sets (_swing_bounds): the uniform-curvature body reshapes about
its middle, and turning towards an obstacle the head has just passed swung link 1 into it (five of
thirteen runs with a contact, before the guard). With COBRA's config/nav.yaml the body reshapes
about its centroid (sampler.reshape_keeps_centroid), so the guard also keeps the stations between its
front and its tail off the obstacle map (sampler.swing_guard_body), and the crawl guard
(_crawl_bounds, sampler.crawl_guard_m) predicts the side-step of the measured crawl; when the crawl
of the current or every allowed curvature runs into the map the robot backs off
(sampler.crawl_blocked_backs_off), unless a curvature on the chosen arc's side passes
(sampler.crawl_forces_toward_arc).

Obstacle map and route (config/nav.yaml map:): each replan adds its view to a world-frame
map (obstacle_map.py: the floor it shows clears the map, its faces are grown into prior discs); the
checks ask the map about points no image shows, and the goal bias steers by the cost to go of a route
on the map (route.py), so the robot goes round clusters whose gaps are narrower than its footprint.

The ground frame of a replan: the robot's pose on the floor (base_link projected, heading = yaw of
base_link's x axis). Both the simulator's batch loop and a planner node call `replan` and then
`follower.update` at the control rate.
"""
import collections
import math
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from .body_model import BodyGeometry, body_poses, middle_pose
from .collision_check import PerceptionCollisionChecker
from .follower import Command, RecedingHorizonFollower
from .obstacle_map import MapParams, ObstacleMap, view_on_floor
from .route import Route
from .sampler import Selection, TrajectorySampler
from .unicycle import arc_poses

STATION_SPACING_M = 0.04        # stations along the body model's shapes (swing guard, turn in place)


def ground_frame(T_world_base: np.ndarray) -> Tuple[float, float, float]:
    """(x, y, heading) of base_link on the floor."""
    T = np.asarray(T_world_base, float)
    return float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0])


def T_world_ground(pose) -> np.ndarray:
    x, y, th = pose
    T = np.eye(4)
    T[:2, :2] = [[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]
    T[:2, 3] = (x, y)
    return T


def world_xy(T_world_g: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(M, 2) points in a ground frame -> world (T_world_g: T_world_ground of that frame)."""
    return np.asarray(xy, float) @ T_world_g[:2, :2].T + T_world_g[:2, 3]


def to_world(poses: np.ndarray, pose) -> np.ndarray:
    """(N, 3) poses in the ground frame of `pose` -> world."""
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    p = np.asarray(poses, float)
    return np.column_stack([x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1], th + p[:, 2]])


@dataclass
class Replan:
    t_s: float
    pose: Tuple[float, float, float]
    selection: Selection
    path_world: Optional[np.ndarray]      # the chosen arc's free prefix, world frame
    reason: str = ""
    route_world: Optional[np.ndarray] = None   # map.route: the route to the goal, world frame


def _from_head(stations_xy: np.ndarray) -> np.ndarray:
    """(N, 2) body stations, tail to head -> (N,) their distance from the head along the body."""
    steps = np.hypot(*np.diff(stations_xy, axis=0).T)
    return np.concatenate([np.cumsum(steps[::-1])[::-1], [0.0]])


class NavPlanner:
    holding = False                        # the loop's on_no_free_arc decides how it stops (LayeredPlanner's may wait)

    def __init__(self, intrinsics, head_width_m: float, sampler_params, follower: RecedingHorizonFollower,
                 body: Optional[BodyGeometry] = None, map_params: Optional[MapParams] = None):
        """body: the robot's body (BodyGeometry.of_robot): the swing, crawl and back-off guards and
        the turn in place judge its sweep; None: they are off (the turn in place blind).
        map_params: config/nav.yaml map: (obstacle_map.py, route.py); source truth leaves
        obstacle_map for the simulator to set (ObstacleMap.from_world); None: no map (source none)."""
        self.intrinsics = intrinsics
        self.head_width_m = head_width_m
        self.sampler_params = sampler_params
        self.follower = follower
        self.geometry = body               # the body's sweep: guards and turns in place (body_model.py)
        self._turning = None
        self._stops = 0                    # replans in a row without a free arc
        self._views = collections.deque(maxlen=max(1, sampler_params.earlier_views))
        self.map_params = map_params if map_params is not None else MapParams(source="none", route=False)
        mp = self.map_params
        # obstacle_map.ObstacleMap: answers for the points no image shows; route.Route: the goal
        # bias steers by its cost to go
        self.obstacle_map = ObstacleMap() if mp.source == "faces" else None
        self.route = Route(mp.cell_m, 0.5 * self.footprint_width_m, pad_m=mp.pad_m,
                           inflated_cost=mp.inflated_cost, max_cells=mp.route_max_cells) if mp.route else None

    @property
    def footprint_width_m(self) -> float:
        """The checked footprint: the head's width plus lateral_margin_m a side, at least 2
        body_clearance_m (the body's swept width around the head's path)."""
        return max(self._width_with_margins(None), 2.0 * self.sampler_params.body_clearance_m)

    def _width_with_margins(self, body: Optional[BodyGeometry]) -> float:
        """The head's width (with a body: the wider of head and body) plus lateral_margin_m a side:
        the footprint at an arc's start (taper, body None) and of the body's sweep."""
        width = self.head_width_m if body is None else max(self.head_width_m, body.width_m)
        return width + 2.0 * self.sampler_params.lateral_margin_m

    def replan(self, t_s: float, ground_image: np.ndarray, T_ground_camera: np.ndarray, pose,
               goal_xy=None, goal_radius_m: float = 0.0, unknown=None, body=None) -> Replan:
        """unknown (the image's unmeasured pixels) is not read: this planner takes the region's edge as
        the obstacle's, wherever it is; nor is body (the joints' angles: its guards place the body as
        uniform arcs)."""
        sp = self.sampler_params
        T_world_g = T_world_ground(pose)
        T_g_world = np.linalg.inv(T_world_g)
        checker = self._checker(T_ground_camera, T_g_world, sp.obstacle_depth_m)
        guarded = sp.swing_guard_m > 0 and self.geometry is not None
        swing_checker = self._checker(T_ground_camera, T_g_world, sp.swing_obstacle_depth_m) if guarded else None
        T_world_camera = T_world_g @ np.asarray(T_ground_camera, float)
        if self.sampler_params.earlier_views:
            self._views.appendleft((ground_image, T_world_camera))
        if self.map_params.source == "faces":
            mp = self.map_params
            faces, dirs, floor = view_on_floor(ground_image, self.intrinsics.K(), T_world_camera, mp.max_range_m,
                                               mp.column_step_px, mp.edge_px)
            self.obstacle_map.add_view(faces, dirs, floor, mp.prior_radius_m, mp.priors_off_own_floor)
        sampler = TrajectorySampler(checker, self.sampler_params, self._width_with_margins(None))
        goal_g = None
        cost_to_go = route_path = None
        if goal_xy is not None and self.route is not None and self.obstacle_map is not None:
            self.route.update(self.obstacle_map.geometry(), pose[:2], goal_xy)
            route = self.route
            route_path = route.path.copy()
            cost_to_go = lambda xy: route.cost_to_go(world_xy(T_world_g, xy))
        if goal_xy is not None:
            g = T_g_world @ np.array([goal_xy[0], goal_xy[1], 0.0, 1.0])
            goal_g = (float(g[0]), float(g[1]))
        sel = sampler.select(ground_image, goal_g, resuming=self._stops > 0, cost_to_go=cost_to_go,
                             goal_radius_m=goal_radius_m)
        if sel.no_free_arc:
            # keep turning the same way as at the previous replan (no dithering); else towards the
            # side whose arcs see more free floor, ties towards the goal
            if self._turning is None:
                left = sum(a.free_m for a in sel.arcs if a.curvature_per_m > 0)
                right = sum(a.free_m for a in sel.arcs if a.curvature_per_m < 0)
                goal_left = goal_g is None or goal_g[1] >= 0
                self._turning = 1.0 if left > right or (left == right and goal_left) else -1.0
            self._stops += 1
            fp = self.follower.params
            can_back_off = fp.back_off and self._back_off_clear(ground_image, swing_checker, T_ground_camera,
                                                                T_g_world)
            if can_back_off and (fp.back_off_replans == 0 or self._stops <= fp.back_off_replans):
                self.follower.back_off_now()
                return Replan(t_s, tuple(pose), sel, None, "no collision-free arc: back off along the track",
                              route_path)
            turn = None
            if self.geometry is not None:
                turn = self._free_turn(checker, ground_image, sel, sp.turn_free_m)
                if turn is None and can_back_off:
                    self.follower.back_off_now()
                    return Replan(t_s, tuple(pose), sel, None,
                                  "no collision-free arc and no turn the body can sweep: back off along the track",
                                  route_path)
                if turn is None:                  # nowhere to back off to: at least a sweep the views show free,
                    turn = self._free_turn(checker, ground_image, sel, 0.0, both_sides=True)   # either side
            if turn is None:
                turn = self._turning * fp.kappa_turn_per_m
            self.follower.stop_and_turn(turn, abs(turn))
            why = " (backing off: the tail's track is blocked)" if fp.back_off and not can_back_off else ""
            return Replan(t_s, tuple(pose), sel, None,
                          f"no collision-free arc: stop and turn in place (kappa {turn:+.2f} /m){why}", route_path)
        self._turning = None
        self._stops = 0
        arc = sel.arc
        keep = arc.s_m <= arc.free_m + 1e-9
        path = to_world(arc.poses[keep], pose)
        reason = f"arc c {arc.curvature_per_m:+.2f}/m, free {arc.free_m:.2f} m"
        bounds = self._swing_bounds(swing_checker, ground_image, T_world_g) if guarded else None
        crawl = bounds
        if bounds is not None and sp.crawl_guard_m > 0:
            toward = self.follower.params.kappa(self.follower.params.speed_m_s * arc.curvature_per_m)
            crawl = self._crawl_bounds(bounds, T_world_g, toward)
            if crawl is None and sp.crawl_blocked_backs_off and self.follower.params.back_off and \
                    self._back_off_clear(ground_image, swing_checker, T_ground_camera, T_g_world):
                # every curvature the swing guard allows crawls the body into the map
                self.follower.back_off_now()
                return Replan(t_s, tuple(pose), sel, None,
                              f"{reason}, kappa {bounds[0]:+.2f}..{bounds[1]:+.2f} /m (swing guard) all crawl "
                              "into the map (crawl guard): back off along the track", route_path)
            crawl = bounds if crawl is None else crawl
        self.follower.set_path(path, arc.curvature_per_m, crawl)
        if bounds is not None:
            reason += f", kappa {bounds[0]:+.2f}..{bounds[1]:+.2f} /m (swing guard)"
        if crawl != bounds:
            reason += f", {crawl[0]:+.2f}..{crawl[1]:+.2f} /m (crawl guard)"
        return Replan(t_s, tuple(pose), sel, path, reason, route_path)

    def _checker(self, T_ground_camera, T_g_world, obstacle_depth_m: float) -> PerceptionCollisionChecker:
        """The current image's checker with the earlier views (newest first, their cameras in the
        current ground frame; non-ground up to obstacle_depth_m beyond a view's ground edge is an
        obstacle)."""
        hidden = None
        if self.obstacle_map is not None:
            T_world_g = np.linalg.inv(T_g_world)
            omap = self.obstacle_map
            hidden = lambda xy: omap.blocked(world_xy(T_world_g, xy))
        checker = PerceptionCollisionChecker(self.intrinsics, T_ground_camera, self.footprint_width_m,
                                             blocked_wins=self.sampler_params.blocked_wins,
                                             hidden_obstacles=hidden,
                                             blocked_wins_depth_m=self.sampler_params.blocked_wins_depth_m)
        for ground_k, T_world_camera_k in self._views:
            checker.add_view(ground_k, T_g_world @ T_world_camera_k, self.sampler_params.horizon_m,
                             obstacle_depth_m)
        return checker

    def _back_off_clear(self, ground, swing_checker, T_ground_camera, T_g_world) -> bool:
        """sampler.back_off_check_m: may the robot back off? Backing off tail first at a
        constant kappa moves every point of the body along the body's own circle into the place of
        the point behind it (body_model.py); only the tail enters new ground: the body's circle
        continued back_off_check_m behind the tail, with the body's footprint (its width + the
        lateral margins). Clear unless the current image, an earlier view (their obstacles
        swing_obstacle_depth_m deep, as the swing guard's) or the obstacle map shows an obstacle
        there; floor none shows counts free (the body came that way). Unchecked (True) without the
        body's geometry or with back_off_check_m 0. Unchecked, backing off drove the tail into
        cylinders the map held. swing_checker: the
        replan's swing-guard checker (the same views, depth and map), None: one is built."""
        sp, g = self.sampler_params, self.geometry
        if g is None or sp.back_off_check_m <= 0:
            return True
        kappa = self.follower.kappa_per_m
        tail = arc_poses(kappa, -2.0 * g.half_length_m, STATION_SPACING_M)[-1]
        track = arc_poses(kappa, -sp.back_off_check_m, STATION_SPACING_M, start=tail)[1:]
        checker = swing_checker if swing_checker is not None else self._checker(
            T_ground_camera, T_g_world, sp.swing_obstacle_depth_m)
        scale = np.full(len(track), checker.width_scale(self._width_with_margins(g)))
        free, known = checker.point_state(checker.footprint_points(track, scale).reshape(-1, 3), ground)
        return not (known & ~free).any()

    def _swing_bounds(self, checker, ground, T_world_g: Optional[np.ndarray] = None,
                      step_per_m: float = 0.25) -> Tuple[float, float]:
        """The swing guard: the body curvatures (lo, hi) around the current kappa the follower may
        bend to until the next replan. Reshaping to kappa moves the body about its middle
        (body_model.body_poses: the head (L^2/8) dkappa to the inside of the turn); a kappa is
        allowed while, for every station within swing_guard_m of the head that moves, the point half
        the body's width + lateral_margin_m ahead of its new place, in the direction it moves, is not
        an obstacle in the current image or an earlier view (`checker`: its obstacles are
        swing_obstacle_depth_m deep; unknown floor counts free: the body lies where the camera
        was). Stepped step_per_m out from the current kappa to each side, up to the gait's range.
        Only the front: further back the model's swing overstates the body's (guarding
        the whole body held kappa for minutes after a cylinder was passed, 60 % of COBRA's depth
        runs against 93 %). swing_guard_tail_m > 0: the stations within it of the tail are
        kept off what the obstacle map holds (the map only: the views saw that floor long ago).
        sampler.reshape_keeps_centroid: the shapes keep the body's centroid, so the middle
        moves too (to the outside of the bend): swing_guard_tail_m 1.5 m guards all of COBRA's body
        behind the front against the map (measured, not kept).
        sampler.swing_guard_body (needs T_world_g, the ground frame in the world): the stations
        between the front and the tail's guard may not come nearer the map's obstacles than the
        crawl guard's clearance (half the body's width + crawl_margin_m), or than they already are
        when they are nearer: moving away from an obstacle the body lies close to is allowed.
        (The lead's reach, half the width + lateral_margin_m, pinned kappa: the robot could hold a
        tight turn for minutes beside the goal.)"""
        fp, g, sp = self.follower.params, self.geometry, self.sampler_params
        kappa_now = self.follower.kappa_per_m
        middle = middle_pose((0.0, 0.0, 0.0), kappa_now, g.half_length_m)
        reach = 0.5 * g.width_m + sp.lateral_margin_m
        now = body_poses(middle, kappa_now, kappa_now, g.half_length_m, STATION_SPACING_M,
                         sp.reshape_keeps_centroid)[-1][:, :2]
        from_head = _from_head(now)
        front = from_head <= sp.swing_guard_m + 1e-9
        # the tail's last metres swing as far as the head; against the
        # obstacle map only (the views show the floor beside the tail long ago, with their shadows)
        back = (from_head[0] - from_head <= sp.swing_guard_tail_m + 1e-9) & ~front
        back &= sp.swing_guard_tail_m > 0 and checker.hidden_obstacles is not None
        # the stations between, against the map's distances
        omap = self.obstacle_map
        body = ~front & ~back
        body &= sp.swing_guard_body and T_world_g is not None and omap is not None
        if body.any():                                  # (an empty map's distances are inf: never nearer)
            clearance = 0.5 * g.width_m + sp.crawl_margin_m                 # as the crawl guard's
            near_now = np.minimum(clearance, omap.distance(world_xy(T_world_g, now[body])))
        bounds = []
        for side in (-1.0, 1.0):
            allowed, n = kappa_now, 1
            while True:
                k = max(-fp.kappa_max_per_m, min(fp.kappa_max_per_m, kappa_now + side * n * step_per_m))
                if side * (k - allowed) <= 1e-9:
                    break                                               # at the gait's range
                new = body_poses(middle, kappa_now, k, g.half_length_m, STATION_SPACING_M,
                                 sp.reshape_keeps_centroid)[-1][:, :2]
                d = new - now
                dist = np.hypot(d[:, 0], d[:, 1])
                moving = front & (dist > 1e-3)
                lead = new[moving] + reach * d[moving] / dist[moving, None]
                free, known = checker.point_state(np.column_stack([lead, np.zeros(len(lead))]), ground)
                if (known & ~free).any():
                    break
                swinging = back & (dist > 1e-3)
                if swinging.any() and np.asarray(checker.hidden_obstacles(
                        new[swinging] + reach * d[swinging] / dist[swinging, None]), bool).any():
                    break
                if body.any() and (omap.distance(world_xy(T_world_g, new[body])) < near_now - 1e-3).any():
                    break
                allowed, n = k, n + 1
            bounds.append(allowed)
        return bounds[0], bounds[1]

    def _crawl_bounds(self, bounds: Tuple[float, float], T_world_g: np.ndarray, toward: Optional[float] = None,
                      step_per_m: float = 0.25) -> Optional[Tuple[float, float]]:
        """sampler.crawl_guard_m: the swing guard's bounds narrowed to the curvatures whose
        crawl keeps the body off the obstacle map. Measured (test/python/test_nav_body_model.py):
        COBRA's bent body does not crawl along its own circle; it moves with its middle along the
        middle's tangent (kappa L/2 off the head's heading) and turns only beyond about 0.35 /m. So each curvature
        (the swing guard's steps, within its bounds) is predicted: the body in its new shape (about
        the middle, body_model.body_poses) carried rigidly with the middle along crawl_guard_m of the
        middle's path (curvature omega(kappa) / speed, omega 0 within crawl_dead_band_per_m). A
        station (beyond the swing guard's front swing_guard_m, whose way the arcs check) may not come
        nearer the map's obstacles than half the body's width + crawl_margin_m, or than it already is
        when it is nearer. If the current kappa passes, the bounds close round it and its passing
        neighbours. If it fails, None (the replan backs off with sampler.crawl_blocked_backs_off,
        else the swing guard's bounds stand), except (sampler.crawl_forces_toward_arc; toward: the
        chosen arc's feed-forward kappa) when a kappa on `toward`'s side of the current one passes:
        the nearest of those is forced (the follower bends that way anyway; forcing against the arc
        can circle the robot off the goal; forcing the nearest passing kappa on either side was
        measured and dropped). Without it a
        station that misses the clearance by a millimetre at the current kappa, while kappas on the
        arc's side pass, makes the robot back off, and back off again beside the same obstacle, until
        the time limit."""
        sp, g, fp = self.sampler_params, self.geometry, self.follower.params
        omap = self.obstacle_map
        if omap is None or omap.geometry().is_empty:
            return bounds
        lo, hi = bounds
        kappa_now = self.follower.kappa_per_m
        n_lo = math.ceil((lo - kappa_now) / step_per_m - 1e-9)
        n_hi = math.floor((hi - kappa_now) / step_per_m + 1e-9)
        ks = sorted({lo, hi, *(kappa_now + n * step_per_m for n in range(n_lo, n_hi + 1))})
        middle = middle_pose((0.0, 0.0, 0.0), kappa_now, g.half_length_m)
        need = 0.5 * g.width_m + sp.crawl_margin_m
        c0, s0 = math.cos(middle[2]), math.sin(middle[2])

        def clear(k: float) -> bool:
            body = body_poses(middle, kappa_now, k, g.half_length_m, STATION_SPACING_M,
                              sp.reshape_keeps_centroid)[-1][:, :2]
            body = body[_from_head(body) > sp.swing_guard_m + 1e-9]
            d = body - middle[:2]
            rel = np.column_stack([c0 * d[:, 0] + s0 * d[:, 1], -s0 * d[:, 0] + c0 * d[:, 1]])
            turning = math.copysign(max(0.0, abs(k) - sp.crawl_dead_band_per_m), k)
            path = arc_poses(fp.omega(turning) / fp.speed_m_s, sp.crawl_guard_m, 0.05, start=middle)
            c, s = np.cos(path[:, 2])[:, None], np.sin(path[:, 2])[:, None]
            xs = path[:, 0:1] + c * rel[None, :, 0] - s * rel[None, :, 1]      # (steps, stations)
            ys = path[:, 1:2] + s * rel[None, :, 0] + c * rel[None, :, 1]
            dist = omap.distance(world_xy(T_world_g, np.column_stack([xs.ravel(), ys.ravel()])))
            dist = dist.reshape(xs.shape)
            return bool((dist[1:].min(axis=0) >= np.minimum(need, dist[0]) - 1e-3).all())

        ok = [clear(k) for k in ks]
        now = min(range(len(ks)), key=lambda i: abs(ks[i] - kappa_now))
        passing = [i for i in range(len(ks)) if ok[i]]
        if not ok[now]:
            if toward is None or not sp.crawl_forces_toward_arc:
                return None
            passing = [j for j in passing if (ks[j] - kappa_now) * (toward - kappa_now) > 0]
        if not passing:
            return None
        i = now if ok[now] else min(passing, key=lambda j: (abs(ks[j] - kappa_now), abs(ks[j])))
        a = b = i
        while a > 0 and ok[a - 1]:
            a -= 1
        while b < len(ks) - 1 and ok[b + 1]:
            b += 1
        return ks[a], ks[b]

    def _free_turn(self, checker, ground, sel: Selection, crawl_m: float,
                   both_sides: bool = False) -> Optional[float]:
        """A turn in place whose reshaping the body can sweep: from the current kappa to
        +-kappa_turn_per_m, then half of it, the turning side first; every shape on the way free
        in the current or an earlier image with the body's footprint (its width + the lateral
        margins; points no view shows count free within the near field, beside and behind the
        camera, as for the arcs), and (crawl_m > 0: sampler.turn_free_m) the tightest candidate arc
        on that side free for crawl_m: the gait crawls on while the body turns, and turning on
        into a cylinder right ahead of the head was a contact with depth (every arc
        0 m free while the tightest kappa was held). None if none is.
        Bending to kappa swings both ends (L^2/8) kappa to the inside: turning blindly
        coiled COBRA's head and tail into what had stopped it."""
        fp, g = self.follower.params, self.geometry
        kappa_now = self.follower.kappa_per_m
        middle = middle_pose((0.0, 0.0, 0.0), kappa_now, g.half_length_m)
        scale = checker.width_scale(self._width_with_margins(g))
        keep = self.sampler_params.turn_keeps_side and not both_sides   # that side or back off
        sides = (self._turning,) if keep else (self._turning, -self._turning)
        for side in sides:
            if crawl_m > 0:
                tightest = max((a for a in sel.arcs if a.curvature_per_m * side > 0),
                               key=lambda a: abs(a.curvature_per_m), default=None)
                if tightest is None or tightest.free_m < crawl_m:
                    continue
            for k in (fp.kappa_turn_per_m, 0.5 * fp.kappa_turn_per_m):
                shapes = np.vstack(body_poses(middle, kappa_now, side * k, g.half_length_m, STATION_SPACING_M,
                                              self.sampler_params.reshape_keeps_centroid))
                blocked, unknown = checker.pose_state(shapes, ground, np.full(len(shapes), scale))
                if not (blocked | unknown).any():
                    return side * k
        return None

    def map_geometry(self):
        """The obstacle map as shapely geometry (None: map.source keeps none): what a run's top view draws."""
        return None if self.obstacle_map is None else self.obstacle_map.geometry()

    def command(self, t_s: float, pose=None) -> Command:
        """pose: base_link's (x, y, theta) on the floor, or None to predict."""
        return self.follower.update(t_s, pose)
