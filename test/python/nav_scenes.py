"""Scenes the nav tests share (a helper module, not a test module): the committed nav config and
camera, ground masks drawn from the floor under that camera, COBRA's body, and planners set up in
front of a wall or bent beside a mapped cylinder."""
import dataclasses

import numpy as np
from shapely.geometry import Point

from snake_autonomy.paths import config_path
from snake_autonomy.perception.ground_region import grow_from_bottom
from snake_autonomy.planning.rectilinear.body_model import BodyGeometry
from snake_autonomy.planning.rectilinear.config import NavConfig, T_ground_camera
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
from snake_autonomy.planning.rectilinear.planner import NavPlanner

CFG = NavConfig.from_yaml(config_path("nav_perception_space.yaml"))   # COBRA, the perception-space planner
K = CFG.intrinsics
T_GC = T_ground_camera(CFG.mount, 0.046)        # the camera 4.6 cm above the floor
HALF_LENGTH_M = 0.755                           # COBRA: (head 0.1565 + 11 x 0.123) / 2, BodyGeometry.of_robot
COBRA = BodyGeometry(half_length_m=HALF_LENGTH_M, width_m=0.09)       # 1.51 m long, 90 mm wide
WALL = dict(boxes=[(0.12, 0.6, -1.0, 1.0)])     # drawn_mask(**WALL): a wall right ahead, no arc is free


def drawn_mask(discs=(), boxes=()):
    """Ground mask of a floor with discs (x, y, r) and axis-aligned boxes (x0, x1, y0, y1) standing
    on it, drawn per pixel from the ray's floor hit, then grown from the bottom (pixel cells)."""
    v, u = np.mgrid[0:K.height, 0:K.width]
    rays = np.dstack([(u - K.cx) / K.fx, (v - K.cy) / K.fy, np.ones(u.shape)]) @ T_GC[:3, :3].T
    o = T_GC[:3, 3]
    hits = rays[..., 2] < -1e-6
    s = np.where(hits, -o[2] / np.where(hits, rays[..., 2], -1), 0)
    x, y = o[0] + s * rays[..., 0], o[1] + s * rays[..., 1]
    ground = hits & (s < 10)
    for cx, cy, r in discs:
        ground &= np.hypot(x - cx, y - cy) > r
    for x0, x1, y0, y1 in boxes:
        ground &= ~((x > x0) & (x < x1) & (y > y0) & (y < y1))
    return grow_from_bottom(ground)


def shifted(dx):
    """T_ground_camera of a camera dx metres along x from the current one (an earlier pose)."""
    T = np.eye(4)
    T[0, 3] = dx
    return T @ T_GC


def walled_planner(**follower_kw):
    """COBRA's planner for a wall right ahead, judging a turn in place by its sweep alone: no crawl
    room asked (turn_free_m 0), the other side tried when the turning side cannot be swept
    (turn_keeps_side off), and the body reshaped about its middle (reshape_keeps_centroid off)."""
    fp = dataclasses.replace(CFG.follower, kappa_rate_per_m_s=0.0, **follower_kw)
    sp = dataclasses.replace(CFG.sampler, turn_free_m=0.0, turn_keeps_side=False, reshape_keeps_centroid=False)
    return NavPlanner(K, 0.09, sp, RecedingHorizonFollower(fp), COBRA)


def planner_with(obstacle, kappa_per_m, guard_m=0.2, dead_band=0.35, keep_centroid=False, tail_m=0.0, **keys):
    """COBRA at the origin heading +x, bent to kappa_per_m, one disc (x, y, r) in the obstacle map;
    by default the middle kept, no tail or body guard and no backing off a blocked crawl: each guard
    alone, as its single runs were measured. keys: further sampler keys."""
    single_guard = dict(swing_guard_body=False, crawl_blocked_backs_off=False)
    sp = dataclasses.replace(CFG.sampler, swing_guard_m=0.2, crawl_guard_m=guard_m,
                             crawl_dead_band_per_m=dead_band, reshape_keeps_centroid=keep_centroid,
                             swing_guard_tail_m=tail_m, **{**single_guard, **keys})
    p = NavPlanner(K, 0.09, sp, RecedingHorizonFollower(CFG.follower), COBRA)
    p.obstacle_map = ObstacleMap(Point(obstacle[:2]).buffer(obstacle[2], 32))
    p.follower._kappa = kappa_per_m
    return p


def swing_bounds(p, T_world_g=None):
    """The swing guard's bounds of planner p in open floor at the origin (T_world_g: the ground frame
    in the world, which the body guard needs)."""
    return p._swing_bounds(p._checker(T_GC, np.eye(4), p.sampler_params.swing_obstacle_depth_m), drawn_mask(),
                           T_world_g)
