"""The RunMission action's message side (nodes/mission_action.py), without ROS: which mission a goal
asks for, and the per-waypoint result built from the decisions of a run."""
import math
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import pytest

from snake_autonomy.missions import MissionError
from snake_autonomy.nodes.mission_action import DecisionSeries, fill_feedback, fill_result, mission_from_goal

NAN = float("nan")


def goal(mission="", mission_yaml="", waypoints=(), name=""):
    return SimpleNamespace(mission=mission, mission_yaml=mission_yaml, waypoints=list(waypoints), name=name)


def pose2d(x, y, theta):
    return SimpleNamespace(x=x, y=y, theta=theta)


def test_a_goal_names_a_provided_mission_a_yaml_text_or_inline_waypoints():
    assert mission_from_goal(goal(mission="star"), None, None).name == "star"
    m = mission_from_goal(goal(mission_yaml="name: y\nwaypoints: [[1, 2, 90]]\ntime_limit_s: 30\n"), None, None)
    assert (m.name, m.waypoints_deg, m.time_limit_s) == ("y", [(1.0, 2.0, 90.0)], 30.0)
    m = mission_from_goal(goal(waypoints=[pose2d(1.0, 0.0, math.pi / 2), pose2d(2.0, 1.0, 0.0)], name="inl"),
                          None, None)
    assert m.name == "inl"
    assert m.waypoints_deg == [(1.0, 0.0, pytest.approx(90.0)), (2.0, 1.0, 0.0)]
    assert mission_from_goal(goal(waypoints=[pose2d(1.0, 0.0, 0.0)]), None, None).name == "inline"


@pytest.mark.parametrize("g, text", [
    (goal(), "got none"),
    (goal(mission="star", waypoints=[pose2d(1, 0, 0)]), "got mission, waypoints"),
    (goal(mission_yaml="waypoints: [[1, 2"), "not valid YAML"),
    (goal(mission_yaml="waypoints: []"), "the list is empty"),
    (goal(waypoints=[pose2d(NAN, 0, 0)]), "waypoints[0]"),
    (goal(mission="no_such_mission"), "file not found"),
])
def test_a_bad_goal_is_refused_naming_the_field(g, text):
    with pytest.raises(MissionError) as err:
        mission_from_goal(g, None, None)
    assert text in str(err.value)


# 500 bytes that expand to 9^9 (387 million) strings: 57 s and 2.8 GB before it was refused
ALIAS_BOMB = ("a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
              + "".join(f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
                        for p, c in zip("abcdefgh", "bcdefghi"))
              + "waypoints: *i\n")


def test_a_mission_yaml_alias_bomb_is_refused_at_once():
    """Run in a process capped at 2 GB of address space, so that an unbounded parse fails there."""
    script = textwrap.dedent("""
        import resource, sys, time
        from types import SimpleNamespace
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))
        from snake_autonomy.missions import MissionError
        from snake_autonomy.nodes.mission_action import mission_from_goal
        goal = SimpleNamespace(mission="", mission_yaml=sys.stdin.read(), waypoints=[], name="")
        t0 = time.perf_counter()
        try:
            mission_from_goal(goal, None, None)
        except MissionError as exc:
            print(f"{time.perf_counter() - t0:.3f}")
            print(exc)
    """)
    try:
        proc = subprocess.run([sys.executable, "-c", script], input=ALIAS_BOMB, capture_output=True, text=True,
                              timeout=90)
    except subprocess.TimeoutExpired:
        pytest.fail("the alias bomb was not refused within 90 s")
    assert proc.returncode == 0 and proc.stdout, proc.stderr[-1500:]
    seconds, message = proc.stdout.split("\n", 1)
    assert float(seconds) < 1.0
    assert "RunMission goal mission_yaml" in message and "anchor &a refused" in message


def test_a_mission_larger_than_any_real_one_is_refused_before_parsing(tmp_path):
    """1000 waypoints with scout stops take 75 KB; a 1 MiB mission_yaml took 6-10 s to parse, with
    mission_node's lock held (mission/abort waited): a mission over MAX_MISSION_BYTES is refused unread."""
    import time
    from snake_autonomy.missions.mission import MAX_MISSION_BYTES
    text = "waypoints:\n" + "  - [1.0, 2.0, 3.0]\n" * (MAX_MISSION_BYTES // 20 + 1)
    t0 = time.perf_counter()
    refused = f"(?s)RunMission goal mission_yaml: .*larger than {MAX_MISSION_BYTES} bytes"
    with pytest.raises(MissionError, match=refused):
        mission_from_goal(goal(mission_yaml=text), None, None)
    big = tmp_path / "big.yaml"
    big.write_text(text)
    with pytest.raises(MissionError, match=f"larger than {MAX_MISSION_BYTES} bytes"):
        mission_from_goal(goal(mission=str(big)), None, None)
    assert time.perf_counter() - t0 < 0.2
    thousand = "waypoints:\n" + "".join(f"  - pose: [{k * 0.5:.3f}, {-k * 0.25:.3f}, {k % 360:.1f}]\n"
                                         f"    scout: {{height_m: 0.2, hold_s: 5}}\n" for k in range(1000))
    assert len(thousand) < MAX_MISSION_BYTES
    assert len(mission_from_goal(goal(mission_yaml=thousand), None, None).waypoints) == 1000


@pytest.mark.parametrize("name", ["../../../../etc/passwd", "/etc/passwd", "star/../../../../../etc/passwd",
                                  "..", "star\x1b[2J"])
def test_a_goal_names_a_mission_only_inside_the_missions_folder(name):
    with pytest.raises(MissionError) as err:
        mission_from_goal(goal(mission=name), None, None)
    text = str(err.value)
    assert "root:" not in text and "\x1b" not in text
    assert "config/missions" in text


def test_a_refusal_never_quotes_a_files_contents(tmp_path):
    secret = tmp_path / "secret.yaml"
    secret.write_text("top-secret-line-of-a-file\n")
    with pytest.raises(MissionError) as err:
        mission_from_goal(goal(mission=str(secret)), None, None)
    assert "top-secret" not in str(err.value) and "expected a mapping" in str(err.value)


def test_problems_quote_a_short_escaped_piece_of_a_value():
    text = 'name: "\\e[2J' + "A" * 500 + '"\nwaypoints: [["' + "B" * 500 + '", 0, 0]]\nextra: "' + "C" * 500 + '"\n'
    with pytest.raises(MissionError) as err:
        mission_from_goal(goal(mission_yaml=text), None, None)
    message = str(err.value)
    assert "waypoints[0][0]" in message and "extra: unknown key" in message
    assert "\x1b" not in message
    for letter in "BC":
        assert letter * 61 not in message


def status(index, reached, distance, yaw=0.1, stale=False, n=2, gait="sidewind"):
    return dict(waypoint_index=index, num_waypoints=n, waypoint_reached=reached, distance=distance,
                yaw_error_abs=yaw, yaw_error_rel=yaw, yaw_error=yaw, mode=1, gait=gait, pose_stale=stale)


def test_the_result_carries_per_waypoint_metrics_and_the_feedback_a_decision():
    series = DecisionSeries()
    for t, st in ((10.0, status(0, False, 1.0)), (11.0, status(1, True, 0.3)),
                  (12.0, status(1, False, NAN, stale=True)), (13.0, status(1, False, 0.8)),
                  (14.0, status(1, False, 0.6))):
        series.add(t, st)
    metrics = series.metrics([(1.0, 0.0, 0.0), (2.0, 0.0, math.pi / 2)], "aborted: test", t0=10.0)
    result = fill_result(SimpleNamespace(), SimpleNamespace, "m", "aborted", "aborted: test", metrics,
                         path_length_m=0.9, run_dir="/r")
    assert (result.mission, result.state, result.waypoints_reached, result.run_dir) == ("m", "aborted", 1, "/r")
    assert result.duration_s == pytest.approx(4.0)
    first, second = result.waypoints
    assert first.reached and first.time_to_reach_s == pytest.approx(1.0)
    assert first.final_distance_m == pytest.approx(0.3)
    assert not second.reached and math.isnan(second.time_to_reach_s)
    assert second.final_distance_m == pytest.approx(0.6) and second.min_distance_m == pytest.approx(0.6)
    assert second.heading_deg == pytest.approx(90.0)
    fb = fill_feedback(SimpleNamespace(), status(1, False, NAN, stale=True, gait="hold"))
    assert (fb.waypoint_index, fb.num_waypoints, fb.gait, fb.pose_stale) == (1, 2, "hold", True)
    assert math.isnan(fb.distance)
