"""Collisions and clearance between the robot and a world's obstacles (geoms named obstacle_<k>).

A collision is any MuJoCo contact between a robot geom (a geom of a robot body) and an obstacle
geom, counted once per contact episode: an (obstacle, robot geom) pair that touches now and has not
touched for more than gap_s (0.2 s) starts an episode (contacts flicker while a link rubs along an
obstacle: measured, a pushing run counted 477 flickers). Call update(data, t_s) after each physics
step or control period (an episode shorter than the update interval can be missed). Each episode is
kept (`episodes`: when, which obstacle, which link, where) so that a run can say where it touched.
"""
import math
from dataclasses import dataclass
from typing import List, Optional, Set, Tuple

import mujoco
import numpy as np

from ..perception.camera_model import OBSTACLE_PREFIX


@dataclass(frozen=True)
class ContactEpisode:
    t_s: float
    obstacle: str          # the obstacle geom's name (obstacle_<k>)
    link: str              # the robot geom's body (base_link, link_<k>)
    x_m: float             # the robot geom's centre on the floor when the episode began
    y_m: float


class CollisionMonitor:
    def __init__(self, model, gap_s: float = 0.2):
        self.model = model
        self.gap_s = gap_s
        self._last_seen = {}
        self.obstacle_geoms = np.array([g for g in range(model.ngeom)
                                        if model.geom(g).name.startswith(OBSTACLE_PREFIX)], int)
        self.robot_geoms = np.array([g for g in range(model.ngeom) if model.geom_bodyid[g] != 0], int)
        self._is_obstacle = np.zeros(model.ngeom, bool)
        self._is_obstacle[self.obstacle_geoms] = True
        self._is_robot = np.zeros(model.ngeom, bool)
        self._is_robot[self.robot_geoms] = True
        self._touching: Set[Tuple[int, int]] = set()
        self.collisions = 0
        self.episodes: List[ContactEpisode] = []
        self.min_clearance_m = float("inf")

    def touching_pairs(self, data) -> Set[Tuple[int, int]]:
        pairs = set()
        for i in range(data.ncon):
            c = data.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            if c.dist > 0:
                continue
            if self._is_obstacle[g1] and self._is_robot[g2]:
                pairs.add((g1, g2))
            elif self._is_obstacle[g2] and self._is_robot[g1]:
                pairs.add((g2, g1))
        return pairs

    def _link(self, geom: int) -> str:
        """The robot geom's body (base_link, link_<k>)."""
        return self.model.body(int(self.model.geom_bodyid[geom])).name or f"geom_{geom}"

    def clearance_m(self, data, distmax_m: float = 1.0) -> float:
        """Smallest distance between a robot geom and an obstacle geom (distmax_m when further)."""
        best = distmax_m
        for o in self.obstacle_geoms:
            for r in self.robot_geoms:
                best = min(best, mujoco.mj_geomDistance(self.model, data, int(o), int(r), distmax_m, None))
        return best

    def update(self, data, clearance: bool = True, t_s: Optional[float] = None) -> int:
        """Count new contact episodes; track the minimum clearance. Returns the new episodes.
        t_s: simulated time (default data.time)."""
        t = float(data.time if t_s is None else t_s)
        now = self.touching_pairs(data)
        started = sorted(pair for pair in now if t - self._last_seen.get(pair, -math.inf) > self.gap_s + 1e-9
                         and pair not in self._touching)
        new = len(started)
        for o, r in started:
            x, y = (float(v) for v in data.geom_xpos[r][:2])
            self.episodes.append(ContactEpisode(t, self.model.geom(o).name, self._link(r), x, y))
        for pair in now:
            self._last_seen[pair] = t
        self._touching = now
        self.collisions += new
        if clearance and len(self.obstacle_geoms):
            self.min_clearance_m = min(self.min_clearance_m, max(0.0, self.clearance_m(data)))
        return new
