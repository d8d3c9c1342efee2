"""The body as its joints lie (body_chain.py): the stations from the chain's forward kinematics, the
body sweep starting from them and reshaping in joint space to the command's biases, and the
navigation loop taking joint_states."""
import dataclasses

import numpy as np
import pytest

from nav_scenes import CFG
from snake_autonomy import _core
from snake_autonomy.paths import robot_yaml
from snake_autonomy.planning.rectilinear.body_chain import BodyChain, BodyState
from snake_autonomy.planning.rectilinear.body_sweep import BodySweep, SweepParams
from snake_autonomy.planning.rectilinear.nav_loop import FOLLOWING, NavLoop

ROBOT = _core.RobotModel.from_yaml(str(robot_yaml("chang_rectilinear")))      # 12 links of 0.07 m
CHAIN = BodyChain(ROBOT)
YAW = np.asarray(_core.CurvatureSteering(ROBOT).yaw_joints)
LEVEL = np.eye(4)


def test_stations_lie_along_the_links_from_base_link_to_the_tail():
    straight = CHAIN.stations(np.zeros(11), np.eye(3), np.array([0.0, 0.1, 0.84]))
    np.testing.assert_allclose(straight, [[0.0, 0.0], [-0.1, 0.0], [-0.84, 0.0]], atol=1e-9)
    q = np.deg2rad(np.linspace(-20, 25, 11))
    frames = CHAIN.frames(q)
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(frames, axis=0), axis=1))])
    np.testing.assert_allclose(CHAIN.stations(q, np.eye(3), along), frames[:, :2], atol=1e-9)
    # the pitch joints lift the links: their shadows on the floor are shorter
    lifted = np.zeros(11)
    lifted[0::2] = 0.5
    assert np.hypot(*CHAIN.stations(lifted, np.eye(3), np.array([0.84]))[0]) < 0.8


def test_bent_sets_the_yaw_joints_to_the_drivers_biases_and_keeps_the_pitch():
    q = np.full(11, 0.3)
    b = CHAIN.bent(q, 2.0)
    np.testing.assert_allclose(b[YAW], 2.0 * np.asarray(_core.CurvatureSteering(ROBOT).spacing_m))
    pitch = np.setdiff1d(np.arange(11), YAW)
    np.testing.assert_allclose(b[pitch], 0.3)


def test_the_sweep_starts_from_the_body_as_its_joints_lie():
    sweep = BodySweep(CHAIN.geometry, CFG.follower, SweepParams(reshape_keeps_centroid=False), CHAIN)
    q = np.zeros(11)
    q[YAW[-1]] = 0.6                                       # the tail swung left, the command straight
    now = BodyState(q, LEVEL)
    body = sweep.body_now(0.0, now)
    tail = CHAIN.frames(q)[-1, :2]
    np.testing.assert_allclose(body[0], tail, atol=1e-9)
    np.testing.assert_allclose(sweep.sweep(0.0, 1.0, 0.2, now).rows[0], body, atol=1e-12)
    assert np.linalg.norm(sweep.body_now(0.0)[0] - tail) > 0.03   # the commanded shape puts it elsewhere


def test_the_reshape_ends_in_the_commanded_shape_about_the_middle():
    sweep = BodySweep(CHAIN.geometry, CFG.follower, SweepParams(reshape_keeps_centroid=False), CHAIN)
    q = np.zeros(11)
    q[YAW] = [0.3, -0.2, 0.1, 0.0, -0.4]
    s = sweep.sweep(0.0, -1.5, 0.0, BodyState(q, LEVEL))
    final = s.rows[s.reshape_rows]
    m = final.shape[0] // 2
    np.testing.assert_allclose(final[m], s.rows[0][m], atol=1e-12)          # the middle stays
    target = CHAIN.stations(CHAIN.bent(q, -1.5), np.eye(3), CHAIN.geometry.half_length_m - sweep._s)

    def pairwise(p):
        return np.linalg.norm(p[:, None] - p[None], axis=-1)
    np.testing.assert_allclose(pairwise(final), pairwise(target), atol=1e-9)   # the command's shape, moved
    assert np.abs(pairwise(final) - pairwise(s.rows[0])).max() > 0.02


def test_while_crawling_each_reshape_shape_is_where_the_crawl_has_carried_it():
    fp = dataclasses.replace(CFG.follower, kappa_rate_per_m_s=0.2)
    in_place = BodySweep(CHAIN.geometry, fp, SweepParams(dead_band_per_m=0.0), CHAIN)
    crawling = BodySweep(CHAIN.geometry, fp, SweepParams(dead_band_per_m=0.0, reshape_while_crawling=True), CHAIN)
    reshape_m = fp.speed_m_s * 1.0 / 0.2                  # kappa 0 -> 1 at 0.2 /m/s, the gait on at speed_m_s
    for travel in (0.3, -0.1):
        a, b = in_place.sweep(0.0, 1.0, travel), crawling.sweep(0.0, 1.0, travel)
        assert a.travel_m[:a.reshape_rows + 1].max() == 0.0                       # reshaped where it lies
        np.testing.assert_allclose(b.travel_m[:b.reshape_rows + 1], reshape_m * np.array([0, 1 / 3, 2 / 3, 1]))
        assert b.travel_m[-1] == pytest.approx(abs(travel))
        m = a.rows.shape[1] // 2
        ahead = b.rows[b.reshape_rows, m, 0] - a.rows[a.reshape_rows, m, 0]     # the middle, the last shape
        assert ahead == pytest.approx(np.sign(travel) * reshape_m, abs=0.01)
        # the same shape (its stations' mutual distances), only carried
        d = [np.linalg.norm(s.rows[s.reshape_rows][:, None] - s.rows[s.reshape_rows][None], axis=-1) for s in (a, b)]
        np.testing.assert_allclose(d[0], d[1], atol=1e-9)
    # a motion shorter than the reshape ends in the shape it reached by then: a third of the way
    short = crawling.sweep(0.0, 1.0, reshape_m / 3)
    np.testing.assert_allclose(short.travel_m, reshape_m / 3 * np.array([0, 1 / 3, 2 / 3, 1]))
    third = crawling.sweep(0.0, 1.0 / 3, reshape_m / 3)
    np.testing.assert_allclose(short.rows, third.rows, atol=1e-9)           # as if a third had been asked
    same = crawling.sweep(0.7, 0.7, 0.3)                   # no reshape: nothing to crawl through
    np.testing.assert_allclose(same.rows, in_place.sweep(0.7, 0.7, 0.3).rows, atol=1e-12)


def _loop():
    cfg = dataclasses.replace(CFG, planner=dataclasses.replace(CFG.planner, kind="layered"))
    k = cfg.intrinsics
    return NavLoop(cfg, 0.051, lambda img: np.ones((k.height, k.width), bool), goal_xy=(3.0, 0.0),
                   body=CHAIN), cfg


def test_the_loop_takes_joint_states_and_refuses_bad_ones():
    loop, cfg = _loop()
    assert loop.on_joints(0.0, np.zeros(10)).startswith("shape")
    assert loop.on_joints(0.0, np.full(11, np.nan)) == "not finite"
    assert loop.on_joints(1.0, np.zeros(11)) is None
    assert "older" in loop.on_joints(0.5, np.zeros(11))
    assert loop.refused["joints"] == 3
    plain = NavLoop(cfg, 0.051, lambda img: img, goal_xy=(3.0, 0.0), body=CHAIN.geometry)
    assert "no body chain" in plain.on_joints(0.0, np.zeros(11))


def test_each_replan_places_the_body_from_the_joints_nearest_its_frame():
    loop, cfg = _loop()
    k = cfg.intrinsics
    frame = np.zeros((k.height, k.width), np.float32)
    T = np.eye(4)
    T[2, 3] = 0.03
    bent = np.zeros(11)
    bent[YAW] = 0.2
    loop.on_joints(0.0, np.zeros(11))
    loop.on_joints(0.1, bent)
    loop.on_pose(0.1, T)
    loop.on_frame(0.1, frame)
    assert loop.tick(0.1).state == FOLLOWING
    np.testing.assert_allclose(loop.body_at(0.1, T).q, bent)
    assert loop.body_at(0.04, T).q.max() == 0.0
    assert loop.replans_without_joints == 0
    # joints older than pose_timeout_s: the replan places the body as the curvature commanded, counted
    t = 0.1 + cfg.replan_period_s
    assert t - 0.1 > loop.pose_timeout_s
    loop.on_pose(t, T)
    loop.on_frame(t, frame)
    assert loop.body_at(t, T) is None
    loop.tick(t)
    assert loop.replans == 2 and loop.replans_without_joints == 1


def test_a_base_tilted_by_the_gait_tilts_the_whole_chain():
    pitch_up = np.eye(4)
    c, s = np.cos(0.4), np.sin(0.4)
    pitch_up[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    level = CHAIN.stations(np.zeros(11), np.eye(3), np.array([0.84]))
    tilted = CHAIN.stations(np.zeros(11), pitch_up[:3, :3], np.array([0.84]))
    assert tilted[0, 0] == pytest.approx(level[0, 0] * c)
