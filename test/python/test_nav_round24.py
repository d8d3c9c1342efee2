"""Issue 13 round 24: the obstacle map takes a view's faces only in runs of neighbouring columns
(map.min_face_run, obstacle_map.face_runs).

A lone face or pair is where a view's ground edge just crosses max_range_m (an obstacle 0.8-0.9 m away,
two columns whose edge came in at 0.80 m) or grazes an obstacle's side; its prior disc along the ray
lay 12 cm beside the cylinder, where COBRA's body later passed (depth world 16 seed 6: the swing guard
held kappa at 0.06 /m for 30 s beside it, README round 24)."""
import dataclasses

import numpy as np
import pytest

from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
from snake_autonomy.planning.rectilinear.follower import RecedingHorizonFollower
from snake_autonomy.planning.rectilinear.obstacle_map import face_runs, view_on_floor
from snake_autonomy.planning.rectilinear.planner import NavPlanner
from test_nav_planning import CFG, K, T_GC, drawn_mask
from test_nav_round11 import COBRA

POST = (0.6, 0.605, 0.15, 0.155)      # a 5 mm post 0.6 m ahead: one or two of every 4th column see it
BOX = (0.6, 0.7, -0.25, -0.15)        # a 10 cm box: a run of faces


def test_face_runs_count_neighbouring_faces_at_a_similar_range():
    is_face = np.array([1, 1, 0, 1, 1, 1, 0, 1, 1], bool)
    rng = np.array([0.50, 0.51, 0.0, 0.60, 0.61, 0.90, 0.0, 0.30, 0.36])
    # a range jump over 0.05 m ends a run, as a gap does
    assert face_runs(is_face, rng, 0.05).tolist() == [2, 2, 0, 2, 2, 1, 0, 1, 1]
    assert face_runs(is_face, rng, 0.5).tolist() == [2, 2, 0, 3, 3, 3, 0, 2, 2]
    assert face_runs(np.zeros(3, bool), np.zeros(3), 0.05).tolist() == [0, 0, 0]
    assert face_runs(np.zeros(0, bool), np.zeros(0), 0.05).tolist() == []


def faces_near(faces, box, within_rad=0.01):
    """The faces on the rays through the box (edge_px puts them a few cm nearer than its side)."""
    x0, x1, y0, y1 = box
    corners = np.arctan2([y0, y0, y1, y1], [x0, x1, x0, x1])
    bearing = np.arctan2(faces[:, 1], faces[:, 0])
    return int(np.sum((bearing > corners.min() - within_rad) & (bearing < corners.max() + within_rad)))


def test_a_lone_face_is_dropped_and_a_run_kept():
    ground = drawn_mask(boxes=[POST, BOX])
    every, _, floor1 = view_on_floor(ground, K.K(), T_GC, 0.8, 4, edge_px=6)
    runs, _, floor3 = view_on_floor(ground, K.K(), T_GC, 0.8, 4, edge_px=6, min_face_run=3)
    assert 1 <= faces_near(every, POST) <= 2
    assert faces_near(runs, POST) == 0
    assert faces_near(runs, BOX) == faces_near(every, BOX) >= 10
    assert floor3.equals(floor1)                      # the floor the view shows is the same


def test_the_planner_maps_the_post_only_with_every_face():
    faces, rays, _ = view_on_floor(drawn_mask(boxes=[POST]), K.K(), T_GC, 0.8, 4, edge_px=6)
    assert len(faces) == 1
    behind_post = faces + 0.05 * rays              # 5 cm behind its face, in the post's shadow
    behind_box = np.array([[0.62, -0.2]])

    def planner_map(min_run):
        mp = dataclasses.replace(CFG.map, min_face_run=min_run)
        p = NavPlanner(K, 0.09, CFG.sampler, RecedingHorizonFollower(CFG.follower), COBRA, map_params=mp)
        p.replan(0.0, drawn_mask(boxes=[POST, BOX]), T_GC, (0.0, 0.0, 0.0), (1.5, 0.0), 0.2)
        return p.obstacle_map

    assert planner_map(1).blocked(behind_post)[0]
    assert not planner_map(3).blocked(behind_post)[0]
    assert planner_map(3).blocked(behind_box)[0]


@pytest.mark.parametrize("key, value, message", [
    ("min_face_run", 0, "map.min_face_run: must be an integer >= 1, got 0"),
    ("min_face_run", -3, "map.min_face_run: must be an integer >= 1, got -3"),
    ("min_face_run", 2.5, "map.min_face_run: must be an integer, got 2.5"),
    ("face_run_jump_m", 0.0, "map.face_run_jump_m: must be > 0, got 0.0"),
])
def test_the_run_keys_are_validated(key, value, message):
    with pytest.raises(NavConfigError, match=message.replace(".", r"\.")):
        NavConfig.from_dict({"map": {key: value}})
