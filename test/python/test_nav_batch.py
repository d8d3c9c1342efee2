"""The closed loop in batch (runs/nav_batch.py) and `snake_autonomy nav run`: the metrics contract."""
import json
import math

import pytest

from snake_autonomy.cli import main as cli_main


def test_nav_run_writes_the_metrics_contract(root, tmp_path):
    out = tmp_path / "run"
    # 14 s: the first camera frame (stamped 0 s, delivered 0.2 s later) is replanned at the first
    # command tick (0.5 s), the next at 10.5 s (every 10 s); the driver's ramp, 13 s of the gait
    assert cli_main(["nav", "run", "--world", str(root / "config" / "worlds" / "one_obstacle.yaml"),
                     "--time-limit", "14", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    for key, kind in (("goal_reached", bool), ("time_s", float), ("collisions", int),
                      ("min_clearance_m", float), ("path_length_m", float), ("replans", int),
                      ("stops_no_free_arc", int)):
        assert isinstance(m[key], kind), (key, m[key])
    assert m["replans"] == 2 and m["stops_no_free_arc"] == 0 and m["collisions"] == 0
    assert not m["goal_reached"] and m["time_s"] >= 14.0
    # the cylinder's face is 0.6 m ahead of the head at the start, less the robot's progress
    assert 0.3 < m["min_clearance_m"] < 0.6
    assert (out / "topview.png").stat().st_size > 0
    assert m["outcome"] == "time_limit" and m["contacts_follow"] == 0
    # one_obstacle's goal disc starts 1.1 m ahead; 12 s of the gait covers about 7 cm
    assert 0.95 < m["closest_to_goal_m"] < 1.1
    assert (out / "contacts.csv").read_text() == "t_s,obstacle,link,x_m,y_m,follower_mode\n"
    assert len(list((out / "frames").glob("replan_*.png"))) == 2
    # replans.csv: one row per replan, the layered planner's 13 candidate arcs each (nav.yaml), what
    # ended each; the cylinder 0.6 m ahead ends the straight one (an obstacle, or the body sweep)
    import csv
    rows = list(csv.DictReader(open(out / "replans.csv")))
    assert [float(r["t_s"]) for r in rows] == pytest.approx([0.5, 10.5], abs=0.001)
    for r in rows:
        arcs = dict(tuple(map(float, a.split(":"))) for a in r["arcs"].split())
        assert len(arcs) == 13 and all(0.0 <= free <= 1.2 for free in arcs.values())
        assert len(r["arc_limits"]) == 13 and set(r["arc_limits"]) <= set("oub-")
        assert r["arc_limits"][6] in "ob" and arcs[0.0] < 0.6
        chosen = float(r["chosen_curvature_per_m"])
        assert float(r["chosen_free_m"]) == arcs[chosen] and chosen != 0.0     # its row matches its pair
        assert r["reason"].startswith(f"arc c {chosen:+.2f}/m")
    assert abs(float(rows[0]["x_m"])) < 0.01 and float(rows[1]["x_m"]) > 0.02
    # commands.csv: every command the loop sent, at its 2 Hz tick: the forward gait with curve + kappa
    commands = list(csv.DictReader(open(out / "commands.csv")))
    assert [float(c["t_s"]) for c in commands] == pytest.approx([0.5 * k for k in range(1, 28)], abs=0.001)
    assert {c["gait"] for c in commands} == {"rectilinear"} and {c["state"] for c in commands} == {"following"}
    assert m["pose_source"] == "mocap" and m["loop_refused"] == {} and m["loop_errors"] == 0
    assert not m["loop_reached"] and m["final_distance_m"] > 1.2 and m["stop_shift_m"] is None


def test_nav_run_refuses_a_bad_world(tmp_path, capsys):
    bad = tmp_path / "w.yaml"
    bad.write_text("start: [0, 0, 0]\ngoal: [1, 1]\n")
    assert cli_main(["nav", "run", "--world", str(bad), "--out", str(tmp_path / "o")]) == 1
    assert "goal_radius_m: missing" in capsys.readouterr().err


def test_cobra_goes_round_two_cylinders_to_the_goal_without_touching_them():
    """The short version of the experiment (README): random world 0 (a cylinder on the
    straight line 1.0 m ahead, another 0.34 m to its left), depth, seed 0, the robot's loop (its
    layered planner) with motion capture: measured reached (at rest inside the disc) at 694.5 s with
    no contact, 0.09 m the closest. About 60 s wall."""
    from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
    from snake_autonomy.runs.nav_experiment import random_corridor
    # the figure was measured on perfect depth renders (the D435i-like model is the nav runs' default)
    result = NavRun(NavRunSpec(random_corridor(0), seed=0, time_limit_s=800.0, keep_frames=False,
                               depth_model="perfect")).run()
    m = result.metrics
    print({k: m[k] for k in ("goal_reached", "time_s", "collisions", "min_clearance_m", "stops_no_free_arc")})
    assert m["goal_reached"] and m["collisions"] == 0 and not m["rolled_over"]
    assert m["min_clearance_m"] > 0.0
    # it went round the first cylinder: base_link left the straight line by more than the cylinder's
    # radius + the head's half width
    assert abs(result.trajectory[:, 2]).max() > 0.054 + 0.045


def test_how_a_run_ended_is_classified():
    """nav_metrics.nav_outcome on hand-made ends: COBRA's tightest circle (gait map) is 0.82 m."""
    import types
    from snake_autonomy.planning.rectilinear.follower import FollowerParams
    from snake_autonomy.runs.nav_experiment import random_corridor
    from snake_autonomy.runs.nav_metrics import nav_outcome
    fp = FollowerParams(speed_m_s=0.00635, omega_per_kappa=0.0077, kappa_max_per_m=1.0)
    assert fp.min_radius_m == pytest.approx(0.825, abs=0.001)

    def outcome(reached=False, rolled=False, contacts=0, stops=(), pose=(0.0, 0.0, 0.0), loop_reached=False):
        replans = [types.SimpleNamespace(path_world=None if s else 1) for s in stops]
        world = random_corridor(0)   # goal (1.4, 0)
        return nav_outcome(world, reached, loop_reached or reached, rolled, contacts, replans,
                           pose, fp.min_radius_m)

    assert outcome(reached=True) == "success"
    assert outcome(reached=True, contacts=3) == "reached_with_contact"
    assert outcome(rolled=True) == "rolled_over"
    # the loop stopped in the disc, the stop left base_link outside it
    assert outcome(loop_reached=True, pose=(1.1, 0.0, 0.0)) == "left_goal"
    # world 9's end (300 s): the goal 0.33 m behind the left shoulder, inside the 0.82 m circle
    assert outcome(pose=(1.72, -0.08, math.radians(44))) == "circling_goal"
    # far from the goal (outside the radius) or ahead of the robot: not circling
    assert outcome(pose=(0.3, 0.0, 0.0)) == "time_limit"
    assert outcome(pose=(0.3, 0.0, 0.0), stops=(0, 1, 1, 0, 1)) == "stopped"
    assert outcome(pose=(0.3, 0.0, 0.0), stops=(1, 1, 0, 0, 0, 1)) == "time_limit"
