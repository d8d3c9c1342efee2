"""The obstacle map (obstacle_map.py): the faces the views show, each with a prior on the obstacle's
unseen extent behind it, answer for the points no image shows. A later view's floor clears what an
earlier one took for an obstacle; a prior is not laid on floor its own view shows
(map.priors_off_own_floor); priors lie along the surface's normal (map.prior_normal_window_m) or as the
shadow between a run of faces' outermost rays (map.prior_shape: shadow) rather than as a disc along
each ray, which reaches its radius beside an obstacle the ray grazes."""
import dataclasses
import math

import numpy as np
import pytest
import shapely
from shapely.geometry import Point, Polygon

from nav_scenes import CFG, COBRA, K, T_GC, drawn_mask
from snake_autonomy.planning.rectilinear.collision_check import PerceptionCollisionChecker
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import (MapParams, ObstacleMap, face_normals, face_shadows,
                                                              view_on_floor)
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from snake_autonomy.runs.nav_experiment import random_corridor


CYL = (0.6, 0.0, 0.06)


def test_faces_lie_on_the_near_side_and_the_prior_covers_the_unseen_far_side():
    pts, dirs, floor = view_on_floor(drawn_mask(discs=[CYL]), K.K(), T_GC, max_range_m=1.5, column_step_px=2)
    assert len(pts) > 10
    r = np.hypot(pts[:, 0] - CYL[0], pts[:, 1] - CYL[1])
    assert np.all(np.abs(r - CYL[2]) < 0.02), r            # on the cylinder's outline
    assert np.all(pts[:, 0] < CYL[0] + 0.01)                # the side facing the camera
    assert np.allclose(np.hypot(*dirs.T), 1.0)
    m = ObstacleMap()
    m.add_view(pts, dirs, floor, 0.1)
    far_side = [[CYL[0] + 0.05, 0.0], [CYL[0] + 0.03, 0.045]]   # no view shows these
    assert m.blocked(np.array(far_side)).all()
    assert not m.blocked(np.array([[0.3, 0.0], [0.6, 0.3], [0.6, -0.3], [0.9, 0.0]])).any()
    # open floor: no faces (the ground reaches the horizon or max_range_m), the floor seen up to 1.5 m
    pts, _, floor = view_on_floor(drawn_mask(), K.K(), T_GC, 1.5)
    assert len(pts) == 0
    assert floor.contains(Point(1.4, 0.0)) and not floor.contains(Point(1.6, 0.0))
    assert not floor.contains(Point(0.03, 0.0))                   # under the camera: not in view


def test_a_later_view_that_shows_floor_clears_what_an_earlier_one_took_for_an_obstacle():
    m = ObstacleMap()
    # a face 0.5 m ahead (e.g. the far floor the depth test marked unsure), then the floor seen there
    m.add_view(np.array([[0.5, 0.0]]), np.array([[1.0, 0.0]]), None, 0.1)
    assert m.blocked(np.array([[0.55, 0.0]]))[0]
    _, _, floor = view_on_floor(drawn_mask(), K.K(), T_GC, 1.5)
    m.add_view(np.zeros((0, 2)), np.zeros((0, 2)), floor, 0.1)
    assert not m.blocked(np.array([[0.55, 0.0]]))[0]
    # a cylinder's own face survives the view that shows it (its floor ends at the face)
    pts, dirs, floor = view_on_floor(drawn_mask(discs=[CYL]), K.K(), T_GC, 1.5, 2, edge_px=6)
    m.add_view(pts, dirs, floor, 0.1)
    assert m.blocked(np.array([[CYL[0], 0.0], [CYL[0] + 0.05, 0.0]])).all()


def test_the_map_knows_the_worlds_obstacles():
    world = random_corridor(6)
    truth = ObstacleMap.from_world(world.obstacles)
    for ob in world.obstacles:
        assert truth.blocked(np.array([[ob.x_m, ob.y_m]]))[0]
        assert not truth.blocked(np.array([[ob.x_m + ob.footprint_radius_m() + 0.01, ob.y_m]]))[0]


def test_a_rotated_box_is_mapped_by_its_corners():
    from snake_autonomy.sim.world_file import Obstacle
    box = Obstacle("box", 1.0, 0.5, size_m=(0.4, 0.1, 0.3), yaw_deg=90.0)
    assert np.allclose(sorted(box.corners()), sorted([(1.05, 0.7), (0.95, 0.7), (0.95, 0.3), (1.05, 0.3)]))
    m = ObstacleMap.from_world([box])
    assert m.blocked(np.array([[1.0, 0.68], [1.0, 0.32]])).all()        # along its long side, now y
    assert not m.blocked(np.array([[1.15, 0.5], [0.85, 0.5]])).any()


def test_the_maps_distance():
    m = ObstacleMap(Point(1.0, 0.0).buffer(0.1, 64))
    d = m.distance(np.array([[1.0, 0.0], [1.3, 0.0], [1.0, -0.5]]))
    assert d == pytest.approx([0.0, 0.2, 0.4], abs=1e-3)
    assert np.isinf(ObstacleMap().distance(np.zeros((2, 2)))).all()


def test_a_hidden_point_inside_a_mapped_obstacle_is_blocked():
    ground = drawn_mask()
    beside = np.array([[0.0, 0.2, 0.0]])             # beside the head: no image shows it
    plain = PerceptionCollisionChecker(K, T_GC, 0.5)
    free, known = plain.point_state(beside, ground)
    assert not known[0]
    m = ObstacleMap()
    m.add_view(np.array([[0.0, 0.15]]), np.array([[0.0, 1.0]]), None, 0.1)
    mapped = PerceptionCollisionChecker(K, T_GC, 0.5, hidden_obstacles=m.blocked)
    free, known = mapped.point_state(beside, ground)
    assert known[0] and not free[0]
    # a point the current image shows is the image's, whatever the map holds
    ahead = np.array([[0.5, 0.0, 0.0]])
    m.add_view(np.array([[0.45, 0.0]]), np.array([[1.0, 0.0]]), None, 0.1)
    mapped = PerceptionCollisionChecker(K, T_GC, 0.5, hidden_obstacles=m.blocked)
    assert mapped.point_state(ahead, ground)[0][0]


def test_the_ros_loop_refuses_the_simulators_truth_map():
    from snake_autonomy.planning.rectilinear.nav_loop import NavLoop
    cfg = dataclasses.replace(CFG, map=MapParams(source="truth"))
    with pytest.raises(ValueError, match="map.source: truth"):
        NavLoop(cfg, 0.09, perception=lambda image: image)


def test_a_run_returns_its_map_and_draws_it(tmp_path):
    """The first replans of world 6 (start facing the cylinder on the start-goal line, 0.72 m ahead of
    the camera): the map holds that cylinder's near side; the run's top view is written with it."""
    from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
    world = random_corridor(6)
    result = NavRun(NavRunSpec(world, seed=7, time_limit_s=25.0, keep_frames=False)).run()
    geom = result.obstacle_map
    assert geom is not None and geom.area > 0
    ahead = world.obstacles[0]                       # (0.78, 0.02), radius 0.06
    assert geom.contains(Point(ahead.x_m - ahead.radius_m + 0.01, ahead.y_m))
    result.write(tmp_path / "run")
    assert (tmp_path / "run" / "topview.png").stat().st_size > 10000


def test_a_views_prior_is_not_laid_on_the_floor_it_shows_beside_the_cylinder():
    pts, dirs, floor = view_on_floor(drawn_mask(discs=[CYL]), K.K(), T_GC, max_range_m=1.5, column_step_px=4,
                                     edge_px=6)
    beside = np.array([[0.6, 0.09], [0.6, -0.09], [0.62, 0.12]])   # floor the view shows, 3-6 cm off the side
    far_side = np.array([[0.65, 0.0], [0.63, 0.045]])             # no view shows these
    old, new = ObstacleMap(), ObstacleMap()
    old.add_view(pts, dirs, floor, 0.1)
    new.add_view(pts, dirs, floor, 0.1, priors_off_own_floor=True)
    assert old.blocked(beside).all() and not new.blocked(beside).any()
    assert old.blocked(far_side).all() and new.blocked(far_side).all()
    lo, hi = new.geometry().bounds[1], new.geometry().bounds[3]
    assert -0.08 < lo < -CYL[2] + 0.005 and CYL[2] - 0.005 < hi < 0.08   # the side within 2 cm
    # a later view's floor still clears an earlier view's disc, with or without the option
    _, _, open_floor = view_on_floor(drawn_mask(), K.K(), T_GC, 1.5)
    new.add_view(np.zeros((0, 2)), np.zeros((0, 2)), open_floor, 0.1, priors_off_own_floor=True)
    assert not new.blocked(far_side).any()


EDGE_CYL = (0.35, -0.2, 0.07)


def edge_view():
    return view_on_floor(drawn_mask(discs=[EDGE_CYL]), K.K(), T_GC, 0.8, 4, edge_px=6)


def angle_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=1), -1.0, 1.0)))


def test_the_normals_point_into_the_cylinder_where_the_rays_graze_it():
    pts, rays, _ = edge_view()
    assert len(pts) >= 10
    inward = np.array([EDGE_CYL[0], EDGE_CYL[1]]) - pts
    inward /= np.hypot(*inward.T)[:, None]
    normals = face_normals(pts, rays, 0.04)
    assert np.allclose(np.hypot(*normals.T), 1.0)
    assert angle_deg(rays, inward).mean() > 40.0          # the rays pass its centre 28-64 deg off
    assert angle_deg(normals, inward).mean() < 15.0       # the fitted normals 1-20 deg off (a 4 cm window
    assert angle_deg(normals, inward).max() < 22.0        # fits a line to a 7 cm cylinder's arc)


def map_of(pts, dirs, floor):
    m = ObstacleMap()
    m.add_view(pts, dirs, floor, 0.1, True)
    return m.geometry()


def test_discs_along_the_normals_cover_the_cylinder_and_reach_less_far_beside_it():
    pts, rays, floor = edge_view()
    cyl = Point(EDGE_CYL[:2]).buffer(EDGE_CYL[2], 64)

    def overshoot(g):                  # the furthest the map's outline lies from the cylinder
        xy = np.vstack([np.asarray(p.exterior.coords) for p in getattr(g, "geoms", [g])])
        return shapely.distance(cyl, shapely.points(xy)).max()

    along_rays, along_normals = map_of(pts, rays, floor), map_of(pts, face_normals(pts, rays, 0.04), floor)
    assert cyl.difference(along_rays).area > 0.05 * cyl.area          # rays: its far side uncovered
    assert cyl.difference(along_normals).area < 0.01 * cyl.area
    assert overshoot(along_rays) > 0.1                                 # the prior radius beside it
    assert overshoot(along_normals) < 0.075


def test_a_walls_faces_get_its_normal_and_a_lone_face_keeps_its_ray():
    # a wall through (0.5, 0) at 40 deg to the view's axis, seen from the origin
    t = np.array([math.cos(math.radians(50.0)), math.sin(math.radians(50.0))])
    pts = np.array([0.5, 0.0]) + np.linspace(-0.05, 0.05, 21)[:, None] * t
    rays = pts / np.hypot(*pts.T)[:, None]
    n = face_normals(pts, rays, 0.04)
    wall_normal = np.array([t[1], -t[0]])                                 # away from the camera
    assert angle_deg(n, np.tile(wall_normal, (len(n), 1))).max() < 0.5
    # fewer than 3 faces within the window: the ray; window 0: the ray (as without normals)
    lone = np.vstack([pts[:1], pts[:1] + [0.3, 0.0]])
    assert np.allclose(face_normals(lone, rays[:2], 0.04), rays[:2])
    assert np.allclose(face_normals(pts, rays, 0.0), rays)


def test_a_surface_the_ray_grazes_is_turned_to_at_most_60_deg_off_the_ray():
    # a wall along the rays (the camera sees it edge on): its normal is 90 deg off them
    pts = np.column_stack([np.linspace(0.4, 0.5, 11), np.zeros(11)])
    rays = np.tile([1.0, 0.0], (11, 1))
    n = face_normals(pts, rays, 0.04)
    assert angle_deg(n, rays) == pytest.approx(np.full(11, 60.0), abs=1e-6)


def test_the_planner_lays_the_discs_along_the_normals_when_set():
    beside = np.array([[EDGE_CYL[0] + 0.12, EDGE_CYL[1]]])   # 5 cm beyond the cylinder's far side

    def planner_map(window):
        mp = dataclasses.replace(CFG.map, prior_normal_window_m=window)
        p = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(CFG.follower), COBRA, map_params=mp)
        p.replan(0.0, drawn_mask(discs=[EDGE_CYL]), T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2)
        return p.obstacle_map

    assert planner_map(0.0).blocked(beside)[0]
    assert not planner_map(0.04).blocked(beside)[0]
    assert planner_map(0.04).blocked(np.array([[EDGE_CYL[0], EDGE_CYL[1] - 0.06]]))[0]   # its far side


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
    cyl = (0.35, -0.2, 0.07)                         # EDGE_CYL: at the image's right edge
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
