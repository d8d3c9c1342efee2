"""metrics.json of one navigation run: one contract for the batch run (runs/nav_batch.NavRun) and the
run recorded through ROS (runs/nav_record.py), each filling NavFacts from what it has (the plant, or
the run's bag) and calling nav_metrics.

Keys: goal_reached (the loop said so and base_link came to rest inside the goal's disc by ground
truth), loop_reached, time_s (to the loop's goal_reached, else to the end), final_distance_m,
stop_shift_m, collisions, min_clearance_m, path_length_m, replans, stops_no_free_arc, rolled_over,
the run's identity (robot, perception, seed, world, flat_belly_fraction, gait, pose_source,
nav_config, on_no_free_arc), closest_to_goal_m, outcome (nav_outcome), loop_refused, loop_errors,
loop_last_error and contacts_<mode> (contact episodes by the follower's mode when they began).
"""
import collections
import math
from dataclasses import dataclass, field
from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np

from snake_autonomy.planning.rectilinear.follower import MODES
from snake_autonomy.sim.world_file import World

#: the run's identity in metrics.json, in this order
IDENTITY_KEYS = ("robot", "perception", "seed", "world", "flat_belly_fraction", "gait", "pose_source",
                 "nav_config", "on_no_free_arc")


@dataclass
class NavFacts:
    world: World
    trajectory: np.ndarray                  # (N, 3) t, x, y of base_link (ground truth), 10 Hz
    t_end_s: float                          # when the run ended (s from its start)
    final_pose: Tuple[float, float, float]  # base_link's x, y, heading at the end (ground truth)
    loop_reached_t_s: Optional[float]       # the loop's first goal_reached, else None
    stop_xy: Optional[Tuple[float, float]]  # base_link then
    collisions: int                         # contact episodes with the obstacles
    min_clearance_m: float                  # nan: never measured
    path_length_m: float
    replans: Sequence[Any]                  # planner.Replan (path_world None: no free arc)
    stops_no_free_arc: int
    rolled_over: bool
    contact_modes: Sequence[str]            # the follower's mode at each contact episode's start
    min_radius_m: float                     # the follower's tightest circle (FollowerParams.min_radius_m)
    identity: Dict[str, Any]                # IDENTITY_KEYS
    loop_refused: Dict[str, int] = field(default_factory=dict)
    loop_errors: int = 0
    loop_last_error: str = ""


def nav_metrics(f: NavFacts) -> Dict[str, Any]:
    world = f.world
    x, y, _ = f.final_pose
    final_m = math.hypot(x - world.goal[0], y - world.goal[1])
    loop_reached = f.loop_reached_t_s is not None
    reached = loop_reached and final_m <= world.goal_radius_m
    by_mode = collections.Counter(f.contact_modes)
    return {"goal_reached": bool(reached), "loop_reached": loop_reached,
            "time_s": round(float(f.t_end_s if not loop_reached else f.loop_reached_t_s), 3),
            "final_distance_m": round(final_m, 4),
            "stop_shift_m": (round(math.hypot(x - f.stop_xy[0], y - f.stop_xy[1]), 4)
                             if loop_reached and f.stop_xy is not None else None),
            "collisions": int(f.collisions),
            "min_clearance_m": float(f.min_clearance_m) if math.isfinite(f.min_clearance_m) else None,
            "path_length_m": round(f.path_length_m, 4), "replans": len(f.replans),
            "stops_no_free_arc": int(f.stops_no_free_arc), "rolled_over": bool(f.rolled_over),
            **{k: f.identity.get(k) for k in IDENTITY_KEYS},
            "closest_to_goal_m": round(closest_to_goal_m(world, f.trajectory), 4),
            "outcome": nav_outcome(world, reached, loop_reached, f.rolled_over, f.collisions, f.replans,
                                   f.final_pose, f.min_radius_m),
            "loop_refused": dict(f.loop_refused), "loop_errors": int(f.loop_errors),
            "loop_last_error": f.loop_last_error,
            **{f"contacts_{m}": by_mode.get(m, 0) for m in MODES}}


def closest_to_goal_m(world: World, trajectory: np.ndarray) -> float:
    """How near base_link came to the goal's disc (0: reached), over the samples (t, x, y)."""
    if not len(trajectory):
        return math.nan
    xy = np.asarray(trajectory)[:, 1:3]
    d = np.hypot(xy[:, 0] - world.goal[0], xy[:, 1] - world.goal[1]).min() - world.goal_radius_m
    return float(max(0.0, d))


def nav_outcome(world: World, reached: bool, loop_reached: bool, rolled: bool, collisions: int,
                replans: Sequence[Any], pose: Sequence[float], min_radius_m: float) -> str:
    """success | reached_with_contact | rolled_over | left_goal (the loop said reached, its hold
    left base_link outside the disc) | circling_goal (at the end the goal lies inside the tightest
    circle the follower drives, within its radius: the arcs circle it) | stopped (3 of the last 5
    replans found no free arc) | time_limit."""
    if reached:
        return "success" if collisions == 0 else "reached_with_contact"
    if rolled:
        return "rolled_over"
    if loop_reached:
        return "left_goal"
    r = min_radius_m
    x, y, th = pose
    dx, dy = world.goal[0] - x, world.goal[1] - y
    gx, gy = math.cos(th) * dx + math.sin(th) * dy, -math.sin(th) * dx + math.cos(th) * dy
    if math.hypot(gx, gy) < r and gx * gx + (abs(gy) - r) ** 2 < r * r:
        return "circling_goal"
    if sum(1 for rp in list(replans)[-5:] if rp.path_world is None) >= 3:
        return "stopped"
    return "time_limit"

