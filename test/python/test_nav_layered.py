"""The layered local planner's layers by behaviour: local map, route, body sweep, critics, recovery,
and a replan through all of them."""
import dataclasses

import numpy as np
import pytest

from nav_scenes import CFG, COBRA, K, T_GC, WALL, drawn_mask
from snake_autonomy.planning.rectilinear.body_sweep import BodySweep, SweepParams, sweep_bounds
from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.critics import Candidate, CriticParams, score
from snake_autonomy.planning.rectilinear.follower import BACK_OFF, FOLLOW, RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.grid_route import GridRoute
from snake_autonomy.planning.rectilinear.layered_planner import LayeredPlanner
from snake_autonomy.planning.rectilinear.local_map import FREE, OCCUPIED, UNKNOWN, LocalMap, LocalMapParams
from snake_autonomy.planning.rectilinear.recovery import BACK_OFF as R_BACK, TURN, WAIT, ProgressChecker, Recovery, \
    RecoveryParams

LAYERED = dataclasses.replace(CFG, planner=dataclasses.replace(CFG.planner, kind="layered"),
                              sampler=dataclasses.replace(CFG.sampler, num_arcs=9))


def camera_at(x=0.0, y=0.0):
    T = np.eye(4)
    T[:2, 3] = (x, y)
    return T @ T_GC


@pytest.fixture
def disc_map():
    """A local map after one view of a disc of radius 0.08 m at (0.5, 0) in front of the camera."""
    m = LocalMap()
    m.add_view(drawn_mask(discs=[(0.5, 0.0, 0.08)]), K.K(), camera_at())
    return m


def test_local_map_marks_the_face_of_what_stands_ahead_and_frees_the_floor(disc_map):
    g = disc_map
    assert g.distance(np.array([[0.42, 0.0]]))[0] < 0.04            # the disc's near side
    assert g.distance(np.array([[0.25, 0.0]]))[0] > 0.08              # (faces sit edge_px rows nearer)
    assert g.seen_free(np.array([[0.3, 0.0], [0.6, 0.2]])).all()   # floor before and beside it
    assert not g.seen_free(np.array([[0.7, 0.0]]))[0]               # hidden behind it: unknown
    grid = g.grid()
    assert (grid == OCCUPIED).any() and (grid == FREE).any() and (grid == UNKNOWN).any()


def test_local_map_marks_no_face_where_the_view_ends_unmeasured():
    """The same image, its region ending at the same rows: below pixels the sensor measured as not
    ground, a face; below pixels it did not measure (a depth camera's range, the grazing floor), none."""
    mask = drawn_mask(discs=[(0.5, 0.0, 0.08)])
    measured, unmeasured = LocalMap(), LocalMap()
    measured.add_view(mask, K.K(), camera_at(), unknown=np.zeros_like(mask))
    unmeasured.add_view(mask, K.K(), camera_at(), unknown=~mask)
    near_side = np.array([[0.42, 0.0]])
    assert measured.distance(near_side)[0] < 0.04
    assert not (unmeasured.grid() == OCCUPIED).any()
    assert unmeasured.seen_free(np.array([[0.3, 0.0]]))[0]         # the floor it saw is free all the same
    # an obstacle nearer than the camera's minimum range has no depth: a region ending unmeasured that
    # near is its face
    near = drawn_mask(discs=[(0.22, 0.0, 0.05)])
    close = LocalMap()
    close.add_view(near, K.K(), camera_at(), unknown=~near)
    assert close.distance(np.array([[0.17, 0.0]]))[0] < 0.04


def test_local_map_clears_a_mark_that_later_views_show_as_floor(disc_map):
    m = disc_map
    face = np.array([[0.42, 0.0]])
    assert m.distance(face)[0] < 0.04
    for _ in range(3):
        m.add_view(drawn_mask(), K.K(), camera_at())                # the same place: floor now
    assert not np.isfinite(m.distance(face)[0]) or m.distance(face)[0] > 0.3
    assert m.seen_free(face)[0]


def test_local_map_rolls_with_the_robot_and_keeps_what_it_saw(disc_map):
    m = disc_map
    before = m.origin.copy()
    m.add_view(np.zeros((K.height, K.width), bool), K.K(), camera_at(x=-3.0))   # a blind view 3 m back
    assert not np.allclose(m.origin, before)
    assert m.distance(np.array([[0.42, 0.0]]))[0] < 0.04


def test_local_map_refuses_inconsistent_thresholds():
    p = LocalMapParams(free_log_odds=1.0)
    assert any("free_log_odds" in e for e in p.validate())


def test_route_goes_through_the_gap_of_a_wall():
    m = LocalMap(LocalMapParams(size_m=4.0))
    m._place((0.0, 0.0))
    i, j, _ = m.cells(np.array([[1.0, y] for y in np.arange(-2.0, 2.0, 0.02) if abs(y - 0.8) > 0.3]))
    m.log_odds[i, j] = 3.0                                           # a wall at x 1 with a gap at y 0.8
    r = GridRoute(0.08, 0.12, 0.045)
    r.update(m, (0.0, 0.0), (2.0, 0.0))
    crossing = r.path[np.argmin(np.abs(r.path[:, 0] - 1.0))]
    assert abs(crossing[1] - 0.8) < 0.2
    c = r.cost_to_go(np.array([[0.0, 0.0], [1.0, 0.8], [2.0, 0.0]]))
    assert c[0] > c[1] > c[2] and c[0] > 2.5                       # the way round, not the straight 2 m


def test_route_reaches_a_goal_outside_the_window_through_its_edge():
    m = LocalMap(LocalMapParams(size_m=2.0))
    m._place((0.0, 0.0))
    r = GridRoute(0.08, 0.12, 0.045)
    r.update(m, (0.0, 0.0), (5.0, 0.0))
    assert r.cost_to_go(np.array([[0.0, 0.0]]))[0] == pytest.approx(5.0, abs=0.1)


def _map_with(points):
    m = LocalMap(LocalMapParams(size_m=4.0))
    m._place((0.0, 0.0))
    i, j, _ = m.cells(np.asarray(points, float))
    m.log_odds[i, j] = 3.0
    return m


def test_body_sweep_reshape_swings_into_an_obstacle_inside_the_bend():
    sweep = BodySweep(COBRA, CFG.follower, SweepParams(reshape_keeps_centroid=False))
    # bending left swings head and tail to the left; an obstacle 0.25 m left of the tail
    m = _map_with([[-1.51, 0.25]])
    left = sweep.check(sweep.sweep(0.0, 2.0, 0.3), m, np.eye(4))
    right = sweep.check(sweep.sweep(0.0, -2.0, 0.3), m, np.eye(4))
    assert left.free_m < 0 and right.free_m == pytest.approx(0.3)


@pytest.mark.parametrize("keeps_centroid", [True, False])
def test_body_sweep_body_now_is_where_every_sweep_starts(keeps_centroid):
    sweep = BodySweep(COBRA, CFG.follower, SweepParams(reshape_keeps_centroid=keeps_centroid))
    for kappa in (-1.2, 0.0, 0.7):
        now = sweep.body_now(kappa)
        assert now.shape == sweep.sweep(kappa, -kappa, 0.3).rows[0].shape
        np.testing.assert_allclose(now, sweep.sweep(kappa, 1.5, 0.3).rows[0], atol=1e-12)
    # a bent body is not the straight one: the ends lie off the x axis
    assert abs(sweep.body_now(1.0)[0, 1]) > 0.05


def test_body_sweep_crawl_stops_before_an_obstacle_ahead():
    sweep = BodySweep(COBRA, CFG.follower, SweepParams())
    m = _map_with([[0.5, 0.0]])
    chk = sweep.check(sweep.sweep(0.0, 0.0, 1.0), m, np.eye(4))
    assert 0.3 < chk.free_m < 0.5                  # the head's half width + margin short of it


def test_body_sweep_lets_a_body_beside_an_obstacle_move_away():
    sweep = BodySweep(COBRA, CFG.follower, SweepParams())
    m = _map_with([[-0.7, 0.08]])                  # 8 cm beside the body's middle: nearer than need
    chk = sweep.check(sweep.sweep(0.0, 0.0, 0.3), m, np.eye(4))
    assert chk.free_m == pytest.approx(0.3)        # straight on: it keeps its distance, not nearer
    assert sweep_bounds(np.array([-1.0, 0.0, 1.0]), np.array([True, True, False]), 1) == (-1.0, 0.0)


def _cand(c, free, clearance=1.0, kappa=None):
    s = np.linspace(0, 1.2, 61)
    return Candidate(c, c / 1.5 if kappa is None else kappa, np.zeros((61, 3)), s, free, clearance)


def test_critics_prefer_longer_free_arcs_then_the_route():
    p = CriticParams()
    cands = [_cand(-1.5, 1.2), _cand(0.0, 0.4), _cand(1.5, 1.1)]
    assert np.argmin(score(cands, p, 1.2, 0.0, 2.0, 3.0)) == 0        # no goal: the longest
    route = np.array([1.0, 0.5, 0.6])
    totals = score(cands, p, 1.2, 0.0, 2.0, 3.0, route)
    assert np.argmin(totals) == 2                  # nearly as long and 0.4 m nearer on the route
    assert cands[2].scores["route"] == pytest.approx(0.1 / 1.2)


def test_critics_clearance_and_curvature_change_break_ties():
    p = CriticParams()
    cands = [_cand(0.0, 1.2, clearance=0.02), _cand(0.0, 1.2, clearance=0.5)]
    assert np.argmin(score(cands, p, 1.2, 0.0, 2.0, 3.0)) == 1
    cands = [_cand(1.5, 1.2, kappa=1.0), _cand(-1.5, 1.2, kappa=-1.0)]
    assert np.argmin(score(cands, p, 1.2, 1.0, 2.0, 3.0)) == 0       # no reshape


def test_recovery_runs_its_sequence_skipping_what_is_not_possible():
    r = Recovery(RecoveryParams(sequence=(R_BACK, R_BACK, TURN)))
    can = {R_BACK: True, TURN: True}
    assert [r.next(can) for _ in range(4)] == [R_BACK, R_BACK, TURN, R_BACK]
    r.reset()
    assert r.next({R_BACK: False, TURN: True}) == TURN
    assert r.next({R_BACK: False, TURN: False}) == WAIT
    assert r.count[WAIT] == 1


def test_progress_checker_finds_a_robot_that_does_not_move():
    pc = ProgressChecker(0.05, 100.0)
    assert not any(pc.stuck(t, (0.001 * t, 0.0)) for t in range(0, 200, 10))     # 1 mm/s: 0.1 m per window
    pc.reset()
    flags = [pc.stuck(t, (0.0, 0.0)) for t in range(0, 200, 10)]
    assert not flags[0] and flags[-1]


def layered(kappa=0.0):
    fp = dataclasses.replace(LAYERED.follower, kappa_rate_per_m_s=0.0)
    f = RecedingHorizonFollower(fp)
    f._kappa = kappa
    return LayeredPlanner(K, 0.09, LAYERED, f, COBRA)


def test_layered_planner_goes_round_an_obstacle_ahead():
    pl = layered()
    r = pl.replan(0.0, drawn_mask(discs=[(0.9, 0.05, 0.08)]), T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2)
    assert r.path_world is not None and pl.follower.mode == FOLLOW
    assert r.selection.arc.curvature_per_m != 0.0
    assert "body sweep" in r.reason
    limits = {a.curvature_per_m: (a.limit, a.free_m) for a in r.selection.arcs}
    assert limits[0.75][0] == "obstacle" and limits[0.75][1] < 0.9     # the disc ends the arc past it
    assert limits[-3.0] == ("", pytest.approx(1.1))                    # the horizon, less margin_m, ends this one


def test_the_layered_planner_leaves_the_bodys_reach_to_the_body_sweep(root):
    """The straight arc goes through a 0.5 m passage (the BARN-like fields' narrowest for COBRA) with
    nav.yaml's body_clearance_m 0.25: the head's footprint is not widened to the body's reach (widened, it
    ended every arc before the passage), the body sweep alone judges the body."""
    passage = drawn_mask(boxes=[(0.4, 1.0, 0.25, 0.6), (0.4, 1.0, -0.6, -0.25)])
    assert LAYERED.sampler.body_clearance_m == pytest.approx(0.25)
    for cfg in (LAYERED, NavConfig.from_yaml(root / "config" / "nav.yaml")):
        f = RecedingHorizonFollower(dataclasses.replace(cfg.follower, kappa_rate_per_m_s=0.0))
        r = LayeredPlanner(K, 0.09, cfg, f, COBRA).replan(0.0, passage, T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2)
        straight = next(a for a in r.selection.arcs if a.curvature_per_m == 0.0)
        assert straight.limit == "" and straight.free_m == pytest.approx(1.1)


def test_layered_planner_backs_off_from_a_wall():
    pl = layered()
    r = pl.replan(0.0, drawn_mask(**WALL), T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2)
    assert r.path_world is None and pl.follower.mode == BACK_OFF
    assert "back off" in r.reason


def test_the_12_link_robots_tightest_arcs_leave_its_cameras_view_beyond_its_seen_floor_band(root):
    from snake_autonomy.planning.rectilinear.body_model import BodyGeometry
    from snake_autonomy.planning.rectilinear.config import T_ground_camera
    chang = NavConfig.from_yaml(root / "config" / "nav_chang_rectilinear.yaml")
    T_gc = T_ground_camera(chang.mount, 0.0255)     # the head's camera 2.55 cm above the floor

    def replan(known_free_m):
        cfg = dataclasses.replace(chang, sampler=dataclasses.replace(chang.sampler, known_free_m=known_free_m),
                                  local_map=dataclasses.replace(chang.local_map, start_free_m=0.0))
        f = RecedingHorizonFollower(dataclasses.replace(cfg.follower, kappa_rate_per_m_s=0.0))
        pl = LayeredPlanner(K, 0.051, cfg, f, BodyGeometry(0.42, 0.051))
        return pl.replan(0.0, drawn_mask(), T_gc, (0.0, 0.0, 0.0), (0.1, 0.45), 0.2)     # the goal beside it
    cut = replan(0.3).selection
    assert max(a.free_m for a in cut.arcs if abs(a.curvature_per_m) >= 3.0) < 0.25      # left the view at ~0.2 m
    assert {a.limit for a in cut.arcs if abs(a.curvature_per_m) >= 3.0} == {"unseen"}    # no obstacle drawn
    assert cut.arc.curvature_per_m < 3.0
    assert chang.sampler.known_free_m <= 0.2
    r = replan(chang.sampler.known_free_m)
    assert r.selection.arc.curvature_per_m == pytest.approx(3.6, abs=0.01)   # the tightest, into the goal's disc


def test_nav_config_validates_the_layered_sections():
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_dict({"planner": {"kind": "dwa"}, "critics": {"route": -1.0},
                             "recovery": {"sequence": ["fly"]}, "local_map": {"cell_m": 0}})
    msg = str(e.value)
    for key in ("planner.kind", "critics.route", "recovery.sequence", "local_map.cell_m"):
        assert key in msg



def test_critics_take_an_arc_into_the_goal_disc_however_short():
    cands = [_cand(-1.5, 1.2), _cand(0.0, 0.3)]
    route = np.array([0.2, -0.02])                 # the short one enters the disc 2 cm deep
    assert np.argmin(score(cands, CriticParams(), 1.2, 0.0, 2.0, 3.0, route)) == 1
    assert cands[1].scores["free_length"] == 0.0


def test_body_sweep_lets_a_modelled_station_inside_an_obstacle_move_but_not_deeper():
    # the uniform-arc model puts the body's middle on a mapped cell the real body is clear of
    sweep = BodySweep(COBRA, CFG.follower, SweepParams(reshape_keeps_centroid=False))
    m = _map_with([[-0.75, 0.0]])
    assert sweep.check(sweep.sweep(0.0, 0.0, 0.3), m, np.eye(4)).free_m == pytest.approx(0.3)
    # bending swings the middle off it (allowed); a second obstacle beside the head still counts
    m2 = _map_with([[-0.75, 0.0], [0.2, 0.09]])
    assert sweep.check(sweep.sweep(0.0, 0.0, 0.3), m2, np.eye(4)).free_m < 0.3


@pytest.mark.parametrize("name", ["nav.yaml", "nav_chang_rectilinear.yaml"])
def test_the_loop_runs_the_layered_planner_its_config_names(root, name):
    from snake_autonomy.planning.rectilinear.nav_loop import FOLLOWING, NO_FREE_ARC, NavLoop
    cfg = NavConfig.from_yaml(root / "config" / name)
    assert cfg.planner.kind == "layered"
    open_floor = drawn_mask()
    loop = NavLoop(cfg, 0.09, lambda img: open_floor if img.any() else np.zeros_like(open_floor),
                   goal_xy=(2.0, 0.0), on_no_free_arc="back_off", body=COBRA)
    assert isinstance(loop.planner, LayeredPlanner)
    frame = np.ones((cfg.intrinsics.height, cfg.intrinsics.width), np.float32)
    base = np.eye(4)
    base[2, 3] = 0.046                               # base_link 4.6 cm above the floor (drawn_mask's camera)
    loop.on_pose(0.0, base)
    loop.on_frame(0.0, frame)
    assert loop.tick(0.0).state == FOLLOWING
    loop.on_pose(10.0, base)
    loop.on_frame(10.0, np.zeros_like(frame))       # a view with no floor: a wall right ahead
    tick = loop.tick(10.0)
    assert tick.state == NO_FREE_ARC and tick.backwards


def test_local_map_knows_the_cells_the_body_lay_on_unless_a_view_marked_them():
    m = _map_with([[0.3, 0.0]])                    # a mark the body's cells reach
    body = np.column_stack([np.linspace(-1.0, 0.3, 30), np.zeros(30)])
    assert not m.seen_free(body).any() and (m.unknown_distance(body[:-1]) == 0).all()
    m.mark_body(body, 0.045)
    seen = m.seen_free(body)
    assert seen[:-1].all() and not seen[-1]        # the marked cell stays an obstacle's
    assert (m.unknown_distance(body[:-1]) > 0).all()
    assert m.unknown_distance(np.array([[-1.0, 0.3]]))[0] == 0.0     # beside the body: nobody saw it


def test_body_sweep_keeps_the_body_on_known_cells_when_asked():
    sweep = BodySweep(COBRA, CFG.follower, SweepParams())
    m = _map_with([[3.0, 3.0]])                    # nothing near: only unknown cells behind the body
    body = sweep.sweep(0.0, 0.0, 0.0).rows[0]
    m.mark_body(body, 0.045)
    back = sweep.sweep(0.0, 0.0, -0.1)
    assert sweep.check(back, m, np.eye(4)).free_m == pytest.approx(0.1)        # unknown counts free
    assert sweep.check(back, m, np.eye(4), known=True).free_m < 0.1             # the tail backs into the unseen
    m.mark_body(body - [0.15, 0.0], 0.045)         # the body lay there before (its track)
    assert sweep.check(back, m, np.eye(4), known=True).free_m == pytest.approx(0.1)


def test_a_body_beside_unknown_cells_backs_off_along_its_track_but_does_not_swing_into_them():
    sweep = BodySweep(COBRA, CFG.follower, SweepParams(reshape_keeps_centroid=False))
    m = _map_with([[3.0, 3.0]])
    body = sweep.sweep(0.0, 0.0, 0.0).rows[0]
    m.mark_body(np.vstack([body - [dx, 0.0] for dx in np.arange(0.0, 0.3, 0.02)]), 0.02)   # a narrow track
    along, steered = sweep.sweep(0.0, 0.0, -0.1), sweep.sweep(0.0, 2.0, -0.1)
    assert m.unknown_distance(along.rows[0]).min() < 0.5 * COBRA.width_m   # unknown cells right beside it
    assert sweep.check(along, m, np.eye(4), known=True).free_m == pytest.approx(0.1)
    assert sweep.check(steered, m, np.eye(4), known=True).free_m < 0       # the reshape swings the ends off it
    assert sweep.check(steered, m, np.eye(4)).free_m == pytest.approx(0.1)  # no obstacle: only the unknown


def test_the_simulators_truth_map_sets_every_cell_the_views_never_showed(root):
    """map.source truth (a diagnostic): the layered planner's local map is the world's, occupied at an
    obstacle behind the camera that no view shows, free elsewhere, whatever the view says."""
    from shapely.geometry import Point
    from snake_autonomy.planning.rectilinear.nav_loop import NavLoop
    from snake_autonomy.planning.rectilinear.obstacle_map import ObstacleMap
    cfg = NavConfig.from_yaml(root / "config" / "nav.yaml")
    cfg = dataclasses.replace(cfg, map=dataclasses.replace(cfg.map, source="truth"))
    world = ObstacleMap(Point(-0.6, 0.0).buffer(0.1))             # behind the robot: never in view
    loop = NavLoop(cfg, 0.09, lambda img: np.zeros((K.height, K.width), bool), goal_xy=(2.0, 0.0),
                   on_no_free_arc="back_off", body=COBRA, obstacle_map=world)
    frame = np.ones((cfg.intrinsics.height, cfg.intrinsics.width), np.float32)
    base = np.eye(4)
    base[2, 3] = 0.046
    loop.on_pose(0.0, base)
    loop.on_frame(0.0, frame)                                      # the view shows no floor at all
    loop.tick(0.0)
    m = loop.planner.map
    assert m.distance(np.array([[-0.6, 0.0]]))[0] == 0.0           # the obstacle's cells: occupied
    assert m.seen_free(np.array([[1.0, 0.5], [-0.6, 0.3]])).all()   # the rest: free
    assert not (m.grid() == UNKNOWN).any()
    with pytest.raises(ValueError, match="map.source: truth"):     # the robot's path has no world to give
        NavLoop(cfg, 0.09, lambda img: img, goal_xy=(2.0, 0.0), body=COBRA)
