"""The length of the shortest forward path of bounded curvature from a pose to a disc (issue 13 round
25), ROS-free: the goal bias's heading-aware cost near the goal (sampler.goal_turn_radius_m).

The route (route.py) is a cost to go on (x, y): it does not know which way the robot faces. Next to
the goal that let COBRA orbit it: its head came level with the goal 0.3-0.5 m beside it, the arcs
that entered the 0.2 m goal disc on paper turned tighter than the body could bend there, and the
robot circled the goal at its turning radius (depth world 16 seeds 6-9, world 9 seeds 1-3). Hybrid
A* (Dolgov, Thrun, Montemerlo, Diebel 2008) guides its search by the larger of two lower bounds, the
cost to go with obstacles and no heading, and the non-holonomic cost with the heading and no
obstacles; sampler.py does the same with the route and this length.

The target is a disc, not a pose (Dubins' problem with a free final heading), which the packaged
Dubins libraries (pose to pose) do not solve, so the length is found here by enumeration: a straight
lead of `leads` lengths, a turn of phi at radius R either way, then straight until the disc (phi
sampled every step_rad: at R 0.5 m and 5 deg, 4 cm), and the same lead and turn to the tangent through
the disc's centre in closed form (never missed by the sampling). Every candidate is a path the robot
can drive, so the shortest bounds the true one (which may turn the other way first, CCS) from above.
"""
import math

import numpy as np


def length_to_disc(poses: np.ndarray, goal_xy, goal_radius_m: float, radius_m: float,
                   step_rad: float = math.radians(5.0), leads=(0.0, 0.25, 0.5, 1.0, 1.5, 2.0)) -> np.ndarray:
    """(M, 3) poses (x, y, heading) -> (M,) the shortest path of curvature at most 1 / radius_m,
    driving forward, from each to the disc of goal_radius_m around goal_xy (0 inside it); leads in
    units of radius_m. Every path is at most the lead + one turn of < 2 pi + the straight."""
    if not radius_m > 0:
        raise ValueError(f"radius_m: must be > 0, got {radius_m}")
    p = np.asarray(poses, float).reshape(-1, 3)
    g = np.asarray(goal_xy, float)
    lead = radius_m * np.asarray(leads, float)[:, None]                      # (L, 1)
    th = p[None, :, 2]                                                      # (1, M)
    qx, qy = p[None, :, 0] + lead * np.cos(th), p[None, :, 1] + lead * np.sin(th)   # (L, M)
    phi = np.arange(0.0, 2.0 * math.pi, step_rad)[:, None, None]            # (F, 1, 1)
    best = np.full(len(p), np.inf)
    for side in (1.0, -1.0):
        cx, cy = qx - side * radius_m * np.sin(th), qy + side * radius_m * np.cos(th)
        h = th + side * phi                                                 # (F, L, M)
        px, py = cx + side * radius_m * np.sin(h), cy - side * radius_m * np.cos(h)
        wx, wy = g[0] - px, g[1] - py
        proj = wx * np.cos(h) + wy * np.sin(h)
        perp2 = wx * wx + wy * wy - proj * proj
        half = np.sqrt(np.maximum(goal_radius_m ** 2 - perp2, 0.0))
        hits = (perp2 <= goal_radius_m ** 2) & (proj + half >= 0.0)
        straight = np.where(hits, np.maximum(proj - half, 0.0), np.inf)
        total = lead[None] + radius_m * phi + straight                      # (F, L, M)
        best = np.minimum(best, total.min(axis=(0, 1)))
        # the same family to the disc's centre in closed form (the sampled rays may all miss a disc
        # far away): the tangent from the turning circle through the centre, less the last
        # min(r, straight) (the disc is entered that much before the centre)
        vx, vy = g[0] - cx, g[1] - cy
        d = np.hypot(vx, vy)
        ok = d > radius_m
        ratio = np.where(ok, radius_m / np.maximum(d, 1e-12), 0.0)
        leave = np.arctan2(vy, vx) + side * np.arcsin(ratio)
        turn = np.mod(side * (leave - th), 2.0 * math.pi)
        tangent = np.sqrt(np.maximum(d * d - radius_m * radius_m, 0.0))
        total = np.where(ok, lead + radius_m * turn + tangent - np.minimum(goal_radius_m, tangent), np.inf)
        best = np.minimum(best, total.min(axis=0))
    inside = np.hypot(p[:, 0] - g[0], p[:, 1] - g[1]) <= goal_radius_m
    return np.where(inside, 0.0, best)
