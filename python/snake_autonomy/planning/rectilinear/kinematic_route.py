"""The route in the robot's own motions, ROS-free: a path it can drive, for the route critic.

grid_route.py's Dijkstra on the map's cells knows no turning circle: its route turns on the spot
round a corner, and a robot whose tightest arc has a radius of 0.28-0.33 m follows it into gaps it
cannot turn into, backs off, and circles. This is the Hybrid-A* of Nav2's Smac planner (Dolgov et
al., "Path planning for autonomous vehicles in unknown semi-structured environments", IJRR 2010),
forward only: states (x, y, heading) with x, y continuous and the heading on `headings` steps
counted from the robot's own heading; motions are arcs of one length with the curvatures
k * step / length (k = -levels..levels; the tightest at sampler.max_curvature_per_m), so every
motion ends on a heading step and the table of motions is computed once; a state closes the cell of
the route's grid (grid_route.py) and heading step it ends in. A motion is valid where the head's
footprint (half its width + sampler.lateral_margin_m) stays clear of the map's occupied cells
(inside the first `start_relax_m`, where the robot lies now, no nearer than it is already); its cost
is its length times the route grid's cell costs (inflation, dead ends), unknown cells optimistic as
there, times `non_straight_penalty` for an arc (Nav2 Smac's, 1.2: without it the search weaves
between equal-cost headings on open floor). The heuristic is the grid route's cost to go (Nav2's
obstacle heuristic), which carries the obstacles; the search stops at the goal's disc (a goal
outside the map's window: at the window cell the grid route reaches it through).

The robot keeps the last plan's path while it is on it and the map finds it clear, unless the new
plan costs `switch_gain` (a fifth) less: replanned from scratch, two ways round an obstacle of
nearly equal cost alternated replan after replan and the robot, turning to each, took neither.

The route critic then scores an arc's end (x, y, heading) by `cost_to_go`: the least, over the
path's points, of the path's cost from the point on + (the distance to the point + the turn to the
path's heading at the turning radius, the arc a robot of that radius needs to turn so far) at the
point's cell cost. Costs are the grid route's: metres, times its cells' costs. Where the search
found no path, the grid route's cost to go stands.

Written here with numpy and heapq rather than OMPL's planners (bench/nav_world_paths uses them on
the true worlds): OMPL's sampling planners draw from one random sequence per process that Python
cannot reseed per plan, so the same map would not give the same route twice in a batch worker, and
the batch and ROS runs of a world must issue the same commands.
"""
import heapq
import math
from typing import Optional

import numpy as np


class KinematicRoute:
    def __init__(self, max_curvature_per_m: float, clearance_m: float, headings: int = 36, levels: int = 3,
                 max_expansions: int = 4000, start_relax_m: float = 0.3, non_straight_penalty: float = 1.2,
                 switch_gain: float = 0.2):
        if not max_curvature_per_m > 0:
            raise ValueError(f"max_curvature_per_m: must be > 0, got {max_curvature_per_m}")
        if not (isinstance(headings, int) and headings >= 8):
            raise ValueError(f"headings: must be an integer >= 8, got {headings!r}")
        self.headings, self.levels = headings, levels
        self.step = 2.0 * math.pi / headings
        self.length_m = levels * self.step / max_curvature_per_m        # the tightest arc turns `levels` steps
        self.radius_m = 1.0 / max_curvature_per_m
        self.clearance_m, self.max_expansions, self.start_relax_m = clearance_m, max_expansions, start_relax_m
        self.switch_gain = switch_gain
        self.turns = np.arange(-levels, levels + 1)                       # heading steps of each motion
        self._penalty = np.where(self.turns != 0, non_straight_penalty, 1.0)
        m = max(2, int(math.ceil(self.length_m / 0.04)))                  # samples a motion (every <= 4 cm)
        s = self.length_m * np.arange(1, m + 1) / m
        c = self.turns[:, None] * self.step / self.length_m               # (P, 1) curvature of each motion
        with np.errstate(divide="ignore", invalid="ignore"):
            th = c * s
            x = np.where(c != 0, np.sin(th) / c, s)
            y = np.where(c != 0, (1.0 - np.cos(th)) / c, 0.0)
        self._motion = np.stack([x, y, c * s + 0.0 * s], axis=-1)        # (P, m, 3) in the start's frame
        self.path = None                       # (K, 3) world x, y, heading of the last plan; None: none found
        self.expansions = 0
        self._goal = None                       # the goal of the last plan (a new goal: no path kept)
        self._rem = self._cell_cost = None      # per path point: cost from it on, its cell's cost

    def plan(self, local_map, grid_route, start_pose, goal_xy, goal_radius_m: float) -> Optional[np.ndarray]:
        """The path from start_pose (x, y, yaw) into the goal's disc, (K, 3) world x, y, heading, also
        kept as .path; None (and .path None) when none is found within max_expansions."""
        goal = np.asarray(goal_xy, float)
        prev = self.path if self._goal is not None and np.array_equal(goal, self._goal) else None
        self.clear()
        self._goal = goal
        if local_map.origin is None or grid_route._field is None:
            return None
        x0, y0, yaw0 = (float(v) for v in start_pose[:3])
        new, outside = self._search(local_map, grid_route, (x0, y0, yaw0), goal_xy, goal_radius_m)
        kept = self._rest_of(prev, local_map, grid_route, (x0, y0, yaw0))
        tail = (lambda path: float(grid_route.cost_to_go(path[-1:, :2])[0]) if outside else 0.0)
        if kept is not None and (new is None or self._costs(new, grid_route, tail(new))[0][0]
                                 > (1.0 - self.switch_gain) * self._costs(kept, grid_route, tail(kept))[0][0]):
            new = kept
        if new is not None:
            self._rem, self._cell_cost = self._costs(new, grid_route, tail(new))
        self.path = new
        return new

    def _costs(self, path, grid_route, tail: float):
        """Per point of the path: its cost from there on (each step's length at its start's cell
        cost, + tail), and its cell's cost."""
        ij = grid_route._index(path[:, :2])
        cell = grid_route._cost[ij[:, 0], ij[:, 1]]
        step = np.hypot(*np.diff(path[:, :2], axis=0).T) * cell[:-1]
        return np.concatenate([np.cumsum(step[::-1])[::-1], [0.0]]) + tail, cell

    def _rest_of(self, path, local_map, grid_route, pose) -> Optional[np.ndarray]:
        """The last plan's path from its point nearest the robot on, if the robot is on it (within two
        motions' length, its heading within the tightest motion's turn) and the map still finds it
        clear; None otherwise. The robot's pose first."""
        if path is None:
            return None
        x0, y0, yaw0 = pose
        d = np.hypot(path[:, 0] - x0, path[:, 1] - y0)
        i = int(np.argmin(d))
        turn = abs(math.remainder(path[i, 2] - yaw0, 2.0 * math.pi))
        if d[i] > 2.0 * self.length_m or turn > self.levels * self.step or i == len(path) - 1:
            return None
        rest = np.vstack([[x0, y0, yaw0], path[i + 1:]])
        clear = local_map.distance(rest[:, :2])
        near = np.hypot(rest[:, 0] - x0, rest[:, 1] - y0) < self.start_relax_m
        need = np.where(near, min(self.clearance_m, float(clear[0]) - 1e-3), self.clearance_m)
        return rest if np.all(clear >= need) else None

    def _search(self, local_map, grid_route, start, goal_xy, goal_radius_m: float):
        """(the Hybrid-A* path from start into the goal's disc or None, whether the goal lies
        outside the map's window)."""
        x0, y0, yaw0 = start
        goal = np.asarray(goal_xy, float)
        H, P, m = self.headings, len(self.turns), self._motion.shape[1]
        # the motions from each heading step k (yaw0 + k step), in the world's axes
        yaw = yaw0 + self.step * np.arange(H)
        cs, sn = np.cos(yaw)[:, None, None], np.sin(yaw)[:, None, None]
        mx, my = self._motion[None, :, :, 0], self._motion[None, :, :, 1]
        table = np.stack([cs * mx - sn * my, sn * mx + cs * my], axis=-1)  # (H, P, m, 2)
        ends = (np.arange(H)[:, None] + self.turns[None, :]) % H         # (H, P) heading step at the end
        d_start = float(local_map.distance(np.array([[x0, y0]]))[0])
        need_near = min(self.clearance_m, d_start - 1e-3)
        cell, shape = grid_route._cell, grid_route._shape
        cost = grid_route._cost
        field_min = float(np.min(grid_route._field))
        outside = bool(np.hypot(*(goal - self._window_point(grid_route, goal))) > cell)
        closed = np.zeros(shape + (H,), bool)
        nodes = [(x0, y0, 0, -1, 0.0)]          # x, y, heading step, parent, g
        h0 = float(grid_route.cost_to_go(np.array([[x0, y0]]))[0])
        heap = [(h0, 0, 0)]
        counter = 1
        self.expansions = 0
        found = None
        while heap and self.expansions < self.max_expansions:
            _, _, n = heapq.heappop(heap)
            x, y, k, _, g = nodes[n]
            i, j = grid_route._index(np.array([[x, y]]))[0]
            if closed[i, j, k]:
                continue
            closed[i, j, k] = True
            self.expansions += 1
            if math.hypot(x - goal[0], y - goal[1]) <= goal_radius_m or (
                    outside and float(grid_route.cost_to_go(np.array([[x, y]]))[0]) <= field_min + self.length_m):
                found = n
                break
            pts = np.array([x, y]) + table[k].reshape(-1, 2)                 # (P m, 2)
            d = local_map.distance(pts).reshape(P, m)
            near = math.hypot(x - x0, y - y0) < self.start_relax_m
            ok = np.all(d >= (need_near if near else self.clearance_m), axis=1)
            if not ok.any():
                continue
            ij = grid_route._index(pts)
            c = cost[ij[:, 0], ij[:, 1]].reshape(P, m).mean(axis=1) * self.length_m * self._penalty
            h = grid_route.cost_to_go(pts.reshape(P, m, 2)[:, -1])
            for p in np.flatnonzero(ok):
                ex, ey = pts[p * m + m - 1]
                gn = g + float(c[p])
                nodes.append((float(ex), float(ey), int(ends[k, p]), n, gn))
                heapq.heappush(heap, (gn + float(h[p]), counter, len(nodes) - 1))
                counter += 1
        if found is None:
            return None, outside
        chain = []
        n = found
        while n >= 0:
            chain.append(n)
            n = nodes[n][3]
        chain.reverse()
        pts = [np.array([[x0, y0, yaw0]])]
        for a, b in zip(chain[:-1], chain[1:]):
            xa, ya, ka = nodes[a][:3]
            p = int(np.flatnonzero(ends[ka] == nodes[b][2])[0])
            xy = np.array([xa, ya]) + table[ka, p]
            pts.append(np.column_stack([xy, yaw0 + self.step * ka + self._motion[p, :, 2]]))
        return np.vstack(pts), outside

    def clear(self) -> None:
        """No path: cost_to_go gives the grid route's."""
        self.path = self._rem = self._cell_cost = None

    @staticmethod
    def _window_point(grid_route, xy):
        ij = grid_route._index(np.asarray(xy, float)[None])[0]
        return grid_route._lo + grid_route._cell * ij

    def cost_to_go(self, poses: np.ndarray, grid_cost: np.ndarray) -> np.ndarray:
        """(M, 3) world x, y, heading -> (M,) cost to go along the path (see the module's doc);
        grid_cost (the grid route's cost to go of the same points) without a path."""
        if self.path is None:
            return np.asarray(grid_cost, float)
        q = np.asarray(poses, float).reshape(-1, 3)
        d = np.hypot(q[:, None, 0] - self.path[None, :, 0], q[:, None, 1] - self.path[None, :, 1])
        turn = np.abs(np.angle(np.exp(1j * (q[:, None, 2] - self.path[None, :, 2]))))
        along = np.min(self._rem[None, :] + self._cell_cost[None, :] * (d + self.radius_m * turn), axis=1)
        return along
