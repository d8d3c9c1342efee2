"""Critics: how the layered planner chooses among the candidate arcs the body sweep left valid.

Shaped like Nav2's DWB controller (dwb_critics: each critic scores a trajectory, the controller
takes the least weighted sum; a trajectory that collides is not scored, here the body sweep's job).
Each critic's score lies in about [0, 1]; the weights are config/nav.yaml `critics:`.
- free_length: 1 - the arc's free length / the horizon (longer free arcs first); 0 for an arc whose
  free prefix enters the goal's disc (it is long enough);
- route: the cost to go (grid_route.py) at the end of the arc's free prefix (Nav2's GoalDist,
  aggregation "last": with the goal behind the robot every prefix passes nearest at its start), less
  the least over the candidates, over the horizon; a prefix entering the goal's disc costs minus its
  deepest point's depth in the disc (an arc entering the disc wins, the one passing nearest the
  centre first: the robot turns less tightly than the tightest arcs, and one grazing the disc misses);
- curvature_change: |kappa - kappa now| over the gait's range (every change reshapes the body and
  swings its ends);
- clearance: how much nearer than `comfort_m` the body's sweep passes an obstacle (beyond half
  its width), over comfort_m;
- curvature: |c| over the tightest arc's (the straightest among equals).
"""
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

CRITICS = ("free_length", "route", "curvature_change", "clearance", "curvature")


@dataclass(frozen=True)
class CriticParams:
    """config/nav.yaml `critics:`; the defaults are its values."""
    free_length: float = 1.0
    route: float = 4.0
    curvature_change: float = 0.3
    clearance: float = 0.5
    curvature: float = 0.05
    comfort_m: float = 0.15          # clearance: sweeps passing nearer than this (beyond half the width) cost
    route_inflation_m: float = 0.25  # route (grid_route.py): cells nearer an obstacle than this cost more
    route_inflated_cost: float = 20.0
    route_dead_end_cost: float = 0.0  # route: each recovery adds this to the cost of the cells round it

    def validate(self) -> List[str]:
        p = [f"{k}: must be >= 0, got {getattr(self, k)}" for k in CRITICS if not getattr(self, k) >= 0]
        if not self.comfort_m > 0:
            p.append(f"comfort_m: must be > 0, got {self.comfort_m}")
        if not self.route_inflation_m > 0:
            p.append(f"route_inflation_m: must be > 0, got {self.route_inflation_m}")
        if not self.route_dead_end_cost >= 0:
            p.append(f"route_dead_end_cost: must be >= 0, got {self.route_dead_end_cost}")
        if not self.route_inflated_cost >= 1:
            p.append(f"route_inflated_cost: must be >= 1, got {self.route_inflated_cost}")
        return p


@dataclass
class Candidate:
    curvature_per_m: float           # the head's path curvature
    kappa_per_m: float               # the body curvature the follower drives it with
    poses: np.ndarray                # (N, 3) the head's arc in the ground frame
    s_m: np.ndarray                  # (N,) arc length
    free_m: float = 0.0              # the valid prefix (head and body sweep), margin taken off
    clearance_m: float = np.inf      # the sweep's least distance to an obstacle beyond half the width
    reshape_clear: bool = True       # the body can reshape to kappa_per_m
    limit: str = ""                  # what ends the prefix: obstacle, unseen, body ("" the horizon)
    scores: Dict[str, float] = field(default_factory=dict)


def score(cands: List[Candidate], params: CriticParams, horizon_m: float, kappa_now: float, kappa_max: float,
          c_max: float, route_cost: Optional[np.ndarray] = None) -> np.ndarray:
    """The weighted sums (lower is better); each candidate's critic scores in its .scores.
    route_cost: per candidate, its prefix's cost to go (LayeredPlanner._route_cost; None: no goal)."""
    route = np.zeros(len(cands))
    if route_cost is not None:
        route = (np.asarray(route_cost, float) - np.min(route_cost)) / horizon_m
    total = np.zeros(len(cands))
    for n, c in enumerate(cands):
        reaches = route_cost is not None and route_cost[n] <= 0.0
        c.scores = {
            "free_length": 0.0 if reaches else 1.0 - min(1.0, c.free_m / horizon_m),
            "route": float(route[n]),
            "curvature_change": abs(c.kappa_per_m - kappa_now) / (2.0 * kappa_max),
            "clearance": float(np.clip((params.comfort_m - c.clearance_m) / params.comfort_m, 0.0, 1.0)),
            "curvature": abs(c.curvature_per_m) / c_max if c_max > 0 else 0.0,
        }
        total[n] = sum(getattr(params, k) * v for k, v in c.scores.items())
    return total
