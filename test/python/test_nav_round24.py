"""Issue 13 round 24: the obstacle map's prior on an obstacle's unseen extent as the floor behind each
run of faces, between the run's outermost rays (map.prior_shape: shadow, obstacle_map.face_shadows),
instead of a disc behind each face.

A disc behind a face where the view's ray grazes an obstacle's side reached its radius (0.1 m) beside
the obstacle. Replaying COBRA depth world 16 seed 8 to 242 s, the map held the floor 12 cm south of
the first cylinder, where the body lay, and the swing guard's tail and body guards kept kappa below
0.84 /m 0.5 m from the goal (README round 24). A convex obstacle lies between the rays that graze
its silhouette."""
import dataclasses
import math

import numpy as np
import pytest
import shapely
from shapely.geometry import Point, Polygon

from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap, face_shadows, view_on_floor
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from test_nav_planning import CFG, K, T_GC, drawn_mask
from test_nav_round11 import COBRA


def test_runs_join_neighbouring_faces_and_split_at_gaps_and_range_jumps():
    # a near box (0.45 m) and a far one (0.6 m) overlapping in the image (no column between their faces),
    # then a gap and a third
    near_box, far_box, apart = (0.45, 0.5, -0.05, 0.01), (0.6, 0.7, 0.0, 0.06), (0.5, 0.55, 0.15, 0.2)
    faces, rays, _, (runs, side) = view_on_floor(drawn_mask(boxes=[near_box, far_box, apart]), K.K(), T_GC, 0.8,
                                                 4, edge_px=6, with_runs=True)
    assert len(np.unique(runs)) == 3 and not side.any()
    assert (np.diff(runs) >= 0).all()                                 # in column order
    rng = np.hypot(*(faces - T_GC[:2, 3]).T)
    for r in np.unique(runs):                                         # each run at one box's range
        assert np.ptp(rng[runs == r]) < 0.05
    plain = view_on_floor(drawn_mask(boxes=[near_box, far_box, apart]), K.K(), T_GC, 0.8, 4, edge_px=6)
    assert len(plain) == 3 and np.array_equal(plain[0], faces)          # without with_runs: as before


def beside_and_uncovered(cyl, shape):
    """One view of a drawn cylinder into a map: (how far the map reaches beside the cylinder, outside the
    wedge of rays the cylinder hides, in m; the fraction of the cylinder the map leaves uncovered)."""
    faces, rays, floor, (runs, side) = view_on_floor(drawn_mask(discs=[cyl]), K.K(), T_GC, 0.8, 4, edge_px=6,
                                                     with_runs=True)
    m = ObstacleMap()
    prior = face_shadows(faces, rays, runs, side, 0.2, 0.01, 0.1) if shape == "shadow" else None
    m.add_view(faces, rays, floor, 0.1, True, prior)
    cam = T_GC[:2, 3]
    v = np.array(cyl[:2]) - cam
    a0, half, reach = math.atan2(v[1], v[0]), math.asin(cyl[2] / np.hypot(*v)), np.hypot(*v) + 0.4
    wedge = Polygon([cam] + [cam + reach * np.array([math.cos(a), math.sin(a)])
                             for a in np.linspace(a0 - half, a0 + half, 40)])
    c = Point(cyl[:2]).buffer(cyl[2], 64)
    out = m.geometry().difference(c.union(wedge))
    beside = 0.0
    if not out.is_empty:
        xy = np.vstack([np.asarray(p.exterior.coords) for p in getattr(out, "geoms", [out])])
        beside = float(shapely.distance(wedge, shapely.points(xy)).max())
    return beside, c.difference(m.geometry()).area / c.area


@pytest.mark.parametrize("cyl", [(0.5, -0.1, 0.07), (0.6, 0.2, 0.05)])
def test_the_shadow_covers_the_cylinder_and_stays_within_its_rays(cyl):
    disc_beside, disc_uncovered = beside_and_uncovered(cyl, "disc")
    shadow_beside, shadow_uncovered = beside_and_uncovered(cyl, "shadow")
    assert disc_beside > 0.09                        # the discs reach about their radius beside it
    assert shadow_beside <= 0.012                    # the shadow: the 1 cm pad
    assert shadow_uncovered < 0.01 and disc_uncovered < 0.01


def test_a_face_at_the_images_side_keeps_its_disc():
    cyl = (0.35, -0.2, 0.07)                         # round 23's cylinder at the image's right edge
    faces, rays, _, (runs, side) = view_on_floor(drawn_mask(discs=[cyl]), K.K(), T_GC, 0.8, 4, edge_px=6,
                                                 with_runs=True)
    assert side.sum() == 1 and len(np.unique(runs)) == 1
    j = int(np.nonzero(side)[0][0])
    beyond = faces[j] + 0.1 * rays[j] + 0.08 * np.array([rays[j, 1], -rays[j, 0]])  # beside its ray, outward
    with_disc = face_shadows(faces, rays, runs, side, 0.2, 0.01, 0.1)
    without = face_shadows(faces, rays, runs, np.zeros_like(side), 0.2, 0.01, 0.1)
    assert with_disc.contains(Point(beyond)) and not without.contains(Point(beyond))


def test_a_lone_face_shadows_a_thin_line_and_runs_split_at_range_jumps():
    faces = np.array([[0.5, 0.0], [0.5, 0.01], [0.7, 0.3]])
    rays = faces / np.hypot(*faces.T)[:, None]
    g = face_shadows(faces, rays, np.array([0, 0, 1]), np.zeros(3, bool), 0.2, 0.01, 0.1)
    parts = sorted(getattr(g, "geoms", [g]), key=lambda p: p.centroid.x)
    assert len(parts) == 2                                   # two runs: two parts
    assert parts[0].area == pytest.approx(0.2 * (0.012 + 0.02), rel=0.15)  # 1-1.4 cm wide quad, grown 1 cm a side
    assert parts[1].area == pytest.approx(0.2 * 0.02, rel=0.15)            # the lone face's ray, grown 1 cm
    assert parts[1].contains(Point(faces[2] + 0.19 * rays[2]))
    assert not g.contains(Point(faces[2] + 0.05 * rays[2] + [0.03, -0.03]))
    assert face_shadows(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, int), np.zeros(0, bool),
                        0.2, 0.01, 0.1).is_empty


def test_the_planner_lays_shadows_when_set():
    cyl = (0.5, -0.1, 0.07)
    # 6 cm off the cylinder's right side, outside the rays it hides, beyond the floor the view shows
    # (the line from its last face to the next column's edge at 0.8 m): the discs hold it
    beside = np.array([[0.47, -0.23]])

    def planner_map(shape):
        mp = dataclasses.replace(CFG.map, prior_shape=shape)
        p = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(CFG.follower), COBRA, map_params=mp)
        p.replan(0.0, drawn_mask(discs=[cyl]), T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2)
        return p.obstacle_map

    assert planner_map("disc").blocked(beside)[0]
    assert not planner_map("shadow").blocked(beside)[0]
    assert planner_map("shadow").blocked(np.array([[0.52, -0.1], [0.59, -0.1]])).all()   # it and behind it


def test_the_prior_shape_is_validated():
    with pytest.raises(NavConfigError, match=r"map\.prior_shape: expected one of disc, shadow, got 'cone'"):
        NavConfig.from_dict({"map": {"prior_shape": "cone"}})
    with pytest.raises(NavConfigError, match=r"map\.prior_pad_m: must be >= 0, got -0\.01"):
        NavConfig.from_dict({"map": {"prior_pad_m": -0.01}})


def test_round_24_settings_in_the_nav_configs():
    """Measured on COBRA and not set (README round 24: depth seeds 5-9 89 -> 88 %, seeds 0-4 93 -> 89 %);
    every robot's config keeps the disc prior, as before."""
    from snake_autonomy.planning.rectilinear.config import nav_config_path
    assert NavConfig.from_yaml().map.prior_shape == "disc"
    for robot in ("chang_rectilinear", "follow_the_leader"):
        assert NavConfig.from_yaml(nav_config_path(robot)).map.prior_shape == "disc"
