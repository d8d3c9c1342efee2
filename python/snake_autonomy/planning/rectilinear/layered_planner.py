"""The layered local planner, ROS-free: one replan of the navigation loop, in Nav2's layers.

    traversability image -> local map (local_map.py: one rolling occupancy grid)
      -> route (grid_route.py: Dijkstra on the map, the global planner's part)
      -> candidate arcs (the head's unicycle arcs, Chang et al. III)
      -> body sweep (body_sweep.py: the one validity check, the measured body of each robot)
      -> critics (critics.py: weighted scores, the least wins)
      -> recovery (recovery.py: back off / turn / wait, with a progress checker; a dead end: an escape
         backing off replan after replan, the place made dearer for the route)
      -> the follower (follower.py: receding-horizon pursuit of the chosen arc, its curvature bounded to
         the run of candidates whose reshape the sweep found clear)

An arc's free prefix ends where the head's footprint (its width + lateral_margin_m a side) comes
nearer an occupied cell than it already is at the start, where the head's path leaves the floor the
views showed within its first known_free_m (the camera's blind near field, blind_m, excepted: the
floor under the head was seen before), or where the body's sweep is no longer clear; margin_m (the
head cap ahead of base_link and a safety distance) comes off it. The body's reach beyond the head's
path is the body sweep's alone: the perception-space planner's widening of the head's footprint to
sampler.body_clearance_m (over footprint_taper_m) is not applied here (with it COBRA's arcs ended at
0.1-0.3 m in the BARN-like fields' 0.5 m passages; docs/navigation_measured.md). Valid arcs are at least min_free_m
long (resume_free_m after a stop). The ground frame of a replan: base_link on the floor (x, y,
heading).
"""
import math
from typing import Optional

import numpy as np

from .body_chain import BodyChain, BodyState
from .body_sweep import BodySweep, sweep_bounds
from .critics import Candidate, score
from .follower import RecedingHorizonFollower
from .grid_route import GridRoute
from .local_map import LocalMap
from .collision_check import prefix_length
from .planner import Replan, T_world_ground, to_world, world_xy
from .recovery import BACK_OFF, TURN, WAIT, ProgressChecker, Recovery
from .sampler import Arc, Selection, candidate_arcs


class LayeredPlanner:
    def __init__(self, intrinsics, head_width_m: float, cfg, follower: RecedingHorizonFollower, body):
        """cfg: the NavConfig (its sampler, local_map, body_sweep, critics, recovery sections); body: the
        robot's BodyChain (body_chain.py: the body as its joints lie) or its BodyGeometry (body_model.py:
        uniform arcs of the commanded curvature)."""
        if body is None:
            raise ValueError("body: the layered planner needs the robot's body (BodyChain(robot) or "
                             "BodyGeometry.of_robot)")
        chain = body if isinstance(body, BodyChain) else None
        body = body.geometry if chain is not None else body
        self.intrinsics, self.cfg, self.follower = intrinsics, cfg, follower
        self.sp = cfg.sampler
        self.head_need_m = 0.5 * head_width_m + self.sp.lateral_margin_m
        self.map = LocalMap(cfg.local_map)
        self.sweep = BodySweep(body, follower.params, cfg.body_sweep, chain)
        self._body = None                    # the replan's BodyState (the joints' angles), None: kappa_now's
        lm = cfg.local_map
        cp = cfg.critics
        rp = cfg.recovery
        self.route = GridRoute(2 * lm.cell_m, cp.route_inflation_m, 0.5 * body.width_m, cp.route_inflated_cost,
                               mark_cost=cp.route_dead_end_cost, mark_radius_m=rp.dead_end_radius_m)
        self._escape = None                  # (x, y): the dead end being backed out of
        self.recovery = Recovery(rp)
        self.progress = ProgressChecker(cfg.recovery.progress_m, cfg.recovery.progress_window_s)
        self.holding = False                 # the last replan chose to wait (the loop holds)
        self.obstacle_map = None             # map.source truth (the simulator's diagnostic): the world's
                                             # obstacles, the local map set from them every replan
        p = self.sp
        self._arcs = candidate_arcs(p)
        s = self._arcs[0][2]
        self._unchecked = (s < cfg.local_map.blind_m) | (s > p.known_free_m)   # need not be seen as floor

    @property
    def footprint_width_m(self) -> float:
        return 2.0 * self.head_need_m

    def replan(self, t_s: float, ground: np.ndarray, T_ground_camera: np.ndarray, pose,
               goal_xy=None, goal_radius_m: float = 0.0, unknown=None, body: Optional[BodyState] = None) -> Replan:
        """unknown: the image's unmeasured pixels (ground_region.Traversability), None for a classifier's.
        body: the joints' angles at the frame's time (with a BodyChain; None: the shape of the curvature
        commanded)."""
        self._body = body
        T_world_g = T_world_ground(pose)
        T_world_camera = T_world_g @ np.asarray(T_ground_camera, float)
        if self.obstacle_map is not None:             # map.source truth: the simulator's diagnostic
            self.map.know(self.obstacle_map, T_world_camera)
        else:
            self.map.add_view(ground, self.intrinsics.K(), T_world_camera, unknown)
        kappa_now = self.follower.kappa_per_m
        body_now = self.sweep.body_now(kappa_now, body)
        half = 0.5 * self.sweep.geometry.width_m
        self.map.mark_body(world_xy(T_world_g, body_now),
                           half + (self.cfg.local_map.start_free_m if self.map.updates == 1 else 0.0))
        route_path = None
        if goal_xy is not None:
            self.route.update(self.map, pose[:2], goal_xy)
            route_path = self.route.path
        cands = [self._candidate(c, poses, s, kappa_now, T_world_g) for c, poses, s in self._arcs]
        sel = Selection([Arc(c.curvature_per_m, c.poses, c.s_m, c.free_m, c.limit) for c in cands], None)
        if self._escape is not None:
            out = self._escaping(t_s, pose, sel, T_world_g, route_path)
            if out is not None:
                return out
        need = max(self.sp.min_free_m, self.sp.resume_free_m) if self.recovery.active else self.sp.min_free_m
        valid = [i for i, c in enumerate(cands) if c.free_m >= need]
        stuck = bool(valid) and self.progress.stuck(t_s, pose[:2])
        if not valid or stuck:
            return self._recover(t_s, pose, sel, cands, T_world_g, goal_xy, route_path,
                                 "no progress" if stuck else "no valid arc")
        fp = self.follower.params
        # the loop stops goal_margin_m inside the disc (the stop's own move): aim there
        ctg = self._route_cost(cands, valid, T_world_g, goal_xy, max(0.0, goal_radius_m - fp.goal_margin_m))
        totals = score([cands[i] for i in valid], self.cfg.critics, self.sp.horizon_m, kappa_now,
                       fp.kappa_max_per_m, self.sp.max_curvature_per_m, ctg)
        best = valid[int(np.argmin(totals))]
        sel.chosen = best
        self.recovery.reset()
        self.holding = False
        arc = cands[best]
        bounds = sweep_bounds(np.array([c.kappa_per_m for c in cands]), np.array([c.reshape_clear for c in cands]),
                              best)
        keep = arc.s_m <= arc.free_m + 1e-9
        path = to_world(arc.poses[keep], pose)
        self.follower.set_path(path, arc.curvature_per_m, bounds)
        reason = (f"arc c {arc.curvature_per_m:+.2f}/m, free {arc.free_m:.2f} m, kappa {bounds[0]:+.2f}.."
                  f"{bounds[1]:+.2f} /m (body sweep)")
        return Replan(t_s, tuple(pose), sel, path, reason, route_path)

    def _candidate(self, c: float, poses: np.ndarray, s: np.ndarray, kappa_now: float, T_world_g) -> Candidate:
        p, fp = self.sp, self.follower.params
        kappa = fp.kappa(fp.speed_m_s * c)
        head = world_xy(T_world_g, poses[:, :2])
        d = self.map.distance(head)
        ok = d >= min(self.head_need_m, d[0] - 1e-3)
        seen = self.map.seen_free(head) | self._unchecked
        head_free = prefix_length(ok & seen, s)
        limit = "" if head_free >= p.horizon_m else ("obstacle" if prefix_length(ok, s) <= head_free else "unseen")
        chk = self.sweep.check(self.sweep.sweep(kappa_now, kappa, p.horizon_m, self._body), self.map, T_world_g)
        free = head_free
        if chk.free_m < free:
            free, limit = max(0.0, chk.free_m), "body"
        return Candidate(c, kappa, poses, s, max(0.0, free - p.margin_m), chk.clearance_m, chk.free_m >= 0, limit)

    def _route_cost(self, cands, valid, T_world_g, goal_xy, goal_radius_m):
        """Per valid candidate, the route's cost to go at the end of its free prefix, or (a prefix
        entering the goal's disc) minus its deepest point's depth in the disc; None without a goal."""
        if goal_xy is None:
            return None
        out = []
        for i in valid:
            c = cands[i]
            n = max(1, int(np.searchsorted(c.s_m, c.free_m, side="right")))
            xy = world_xy(T_world_g, c.poses[:n, :2])
            dist = np.hypot(xy[:, 0] - goal_xy[0], xy[:, 1] - goal_xy[1])
            inside = dist <= goal_radius_m
            out.append(float(np.min(dist[inside]) - goal_radius_m) if inside.any()
                       else float(self.route.cost_to_go(xy[-1:])[0]))
        return np.array(out)

    def _recover(self, t_s, pose, sel, cands, T_world_g, goal_xy, route_path, cause) -> Replan:
        rp = self.cfg.recovery
        kappa_now = self.follower.kappa_per_m
        self.progress.reset()
        if self.cfg.critics.route_dead_end_cost > 0 or rp.escape_after:
            self.route.mark(pose[:2])     # dead ends: only where the route's cost or the escape counts them
        if self.recovery.side is None:
            self.recovery.side = self._turn_side(cands, T_world_g, goal_xy)
        if rp.escape_after and self.route.marks_near(pose[:2]) >= rp.escape_after:
            self._escape = (float(pose[0]), float(pose[1]))
            out = self._escaping(t_s, pose, sel, T_world_g, route_path)
            if out is not None:
                return out
        back = self._free_back_off(kappa_now, T_world_g)
        turn = self._free_turn(kappa_now, T_world_g)
        b = self.recovery.next({BACK_OFF: back is not None, TURN: turn is not None})
        self.holding = b == WAIT
        if b == BACK_OFF:
            self.follower.back_off_now(back)
            why = (f"{cause}: back off along the track" if back == kappa_now else
                   f"{cause}: back off steering (kappa {back:+.2f} /m)")
        elif b == TURN:
            self.follower.stop_and_turn(turn, abs(turn))
            why = f"{cause}: turn in place (kappa {turn:+.2f} /m)"
        else:
            why = f"{cause}: wait (no back-off or turn the body sweep finds clear)"
        return Replan(t_s, tuple(pose), sel, None, why, route_path)

    def _turn_side(self, cands, T_world_g, goal_xy) -> float:
        """Towards the side of the candidate whose end has the least cost to go (the route's side);
        without a goal, the side with more free length."""
        if goal_xy is not None:
            ends = np.array([world_xy(T_world_g, c.poses[-1:, :2])[0] for c in cands])
            best = cands[int(np.argmin(self.route.cost_to_go(ends)))]
            if best.curvature_per_m != 0:
                return math.copysign(1.0, best.curvature_per_m)
        left = sum(c.free_m for c in cands if c.curvature_per_m > 0)
        right = sum(c.free_m for c in cands if c.curvature_per_m < 0)
        return 1.0 if left >= right else -1.0

    def _escaping(self, t_s, pose, sel, T_world_g, route_path) -> Optional[Replan]:
        """Back off out of the dead end at self._escape while base_link is nearer it than escape_m and
        a back-off is clear (its own track first); None (the escape over) otherwise."""
        d = math.hypot(pose[0] - self._escape[0], pose[1] - self._escape[1])
        back = None
        if d < self.cfg.recovery.escape_m:
            back = self._free_back_off(self.follower.kappa_per_m, T_world_g, track_first=True)
        if back is None:
            self._escape = None
            return None
        self.holding = False
        self.follower.back_off_now(back)
        return Replan(t_s, tuple(pose), sel, None, f"dead end: back off (kappa {back:+.2f} /m, {d:.2f} of "
                      f"{self.cfg.recovery.escape_m:.2f} m)", route_path)

    def _free_back_off(self, kappa_now: float, T_world_g, track_first: bool = False) -> Optional[float]:
        """The body curvature to back off with, whose reshape and recovery.back_off_m of backwards crawl
        the body sweep finds clear; None if none is. With back_off_steer: against the recovery's side
        first (backing, the body turns the other way round: a car's multi-point turn, so a back-off
        does not undo the turn in place before it), kappa_turn_per_m then half of it, then straight,
        then the curvature held (the body's own track); without it the curvature held only. track_first
        (an escape): the curvature held first, then straight (then the steered ones)."""
        fp, rp = self.follower.params, self.cfg.recovery
        k = fp.kappa_turn_per_m
        side = self.recovery.side or 1.0
        steer = (-side * k, -side * 0.5 * k) if rp.back_off_steer else ()
        if track_first:
            order = (kappa_now, 0.0) + steer[::-1]
        else:
            order = steer + ((0.0, kappa_now) if rp.back_off_steer else (kappa_now,))
        for kappa in order:
            chk = self.sweep.check(self.sweep.sweep(kappa_now, kappa, -rp.back_off_m, self._body), self.map, T_world_g,
                                   rp.known_only)
            if chk.free_m >= rp.back_off_m - 1e-9:
                return kappa
        return None

    def _free_turn(self, kappa_now: float, T_world_g) -> Optional[float]:
        """A turn in place whose reshape and crawl (recovery.turn_crawl_m) the body sweep finds clear:
        the recovery's side first, kappa_turn_per_m then half of it; None if none is."""
        fp, rp = self.follower.params, self.cfg.recovery
        for side in (self.recovery.side, -self.recovery.side):
            for k in (fp.kappa_turn_per_m, 0.5 * fp.kappa_turn_per_m):
                sweep = self.sweep.sweep(kappa_now, side * k, rp.turn_crawl_m, self._body)
                chk = self.sweep.check(sweep, self.map, T_world_g, rp.known_only)
                if chk.free_m >= rp.turn_crawl_m - 1e-9:
                    return side * k
        return None

    def map_geometry(self):
        """The local map's occupied cells as shapely geometry: what a run's top view draws."""
        return self.map.geometry()

    def command(self, t_s: float, pose=None):
        return self.follower.update(t_s, pose)

