"""Mission files: the provided missions load; a bad mission is refused with every problem listed."""
import math
import subprocess
import sys
import textwrap

import pytest

from snake_autonomy.cli import main as cli_main
from snake_autonomy.control import WaypointTracker
from snake_autonomy.missions import MISSIONS_DIR, MissionError, load_mission, validate_mission


@pytest.mark.parametrize("name,count", [("single_waypoint", 1), ("star", 5), ("bidirectional", 8),
                                        ("disturbance", 2)])
def test_provided_missions_load(name, count):
    mission = load_mission(MISSIONS_DIR / f"{name}.yaml")
    assert len(mission.waypoints) == count
    WaypointTracker(mission.waypoints, **mission.tracker_kwargs())   # accepted by the tracker
    assert mission.gaits["stop"] == "hold"


def test_single_waypoint_is_the_origin_heading_zero():
    assert load_mission("single_waypoint").waypoints == [(0.0, 0.0, 0.0)]


def test_bidirectional_returns_home_between_targets():
    wps = load_mission("bidirectional").waypoints
    assert [(x, y) for x, y, _ in wps[1::2]] == [(0.0, 0.0)] * 4
    assert len({(x, y) for x, y, _ in wps[0::2]}) == 4


def test_star_vertices_are_144_degrees_apart_on_one_circle():
    wps = load_mission("star").waypoints
    radii = [math.hypot(x, y) for x, y, _ in wps]
    assert max(radii) - min(radii) < 1e-2
    angles = [math.degrees(math.atan2(y, x)) for x, y, _ in wps]
    for a, b in zip(angles, angles[1:]):
        assert (b - a) % 360 == pytest.approx(144.0, abs=0.1)


def test_minimal_form_and_units():
    m = validate_mission({"waypoints": [[1, 2, 90]]}, "m.yaml")
    assert m.waypoints[0] == pytest.approx((1.0, 2.0, math.pi / 2))
    assert m.tracker_params["d_th"] == 0.35
    assert m.time_limit_s is None and m.name == "m"


def test_overrides():
    m = validate_mission({"waypoints": [[0, 0, 0]], "tracker": {"psi_wp_deg": 25, "d_th_m": 0.2},
                          "gaits": {"sidewind": "turn_left"}, "time_limit_s": 60}, "m")
    assert m.tracker_params["psi_wp"] == pytest.approx(math.radians(25))
    assert m.tracker_params["d_th"] == 0.2
    assert m.gaits["sidewind"] == "turn_left" and m.time_limit_s == 60.0


BAD = textwrap.dedent("""
    name: bad
    waypoints:
      - [0, 0, 0]
      - [0, 0, 0]
      - [1, .nan, 0]
      - [2, 2]
      - [3, "three", 0]
      - [4, 4, .inf]
    gaits:
      sidewind: slither
      wiggle: sidewind
    tracker:
      psi_wp_deg: 50
      kp: "high"
    time_limit_s: 0
    colour: red
""")


def test_every_problem_is_listed(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text(BAD)
    with pytest.raises(MissionError) as err:
        load_mission(f)
    problems = err.value.problems
    expected = [
        "waypoints[1]: duplicate of waypoints[0] [0.0, 0.0, 0.0]",
        "waypoints[2][1] (y_m): must be finite, got nan",
        "waypoints[3]: expected [x_m, y_m, heading_deg], got [2, 2]",
        "waypoints[4][1] (y_m): expected a number, got 'three'",
        "waypoints[5][2] (heading_deg): must be finite, got inf",
        "gaits.sidewind: unknown gait 'slither'",
        "gaits.wiggle: unknown tracker gait (value 'sidewind')",
        "tracker.kp: must be a finite number, got 'high'",
        "time_limit_s: must be a positive number of seconds up to 86400, got 0",
        "colour: unknown key (value 'red')",
    ]
    for e in expected:
        assert any(p.startswith(e) for p in problems), f"{e!r} not in {problems}"
    assert len(problems) == len(expected)


def test_inconsistent_thresholds_name_the_key():
    with pytest.raises(MissionError) as err:
        validate_mission({"waypoints": [[0, 0, 0]], "tracker": {"psi_wp_deg": 50}}, "m")
    assert err.value.problems == ["tracker.psi_wp_deg: must not exceed psi_turn (40 deg), got 50 deg (value 50)"]


@pytest.mark.parametrize("data,message", [
    ({}, "waypoints: missing"),
    ({"waypoints": []}, "waypoints: the list is empty"),
    ({"waypoints": "here"}, "waypoints: expected a list"),
    ([1, 2], "expected a mapping"),
])
def test_missing_or_malformed_waypoints(data, message):
    with pytest.raises(MissionError) as err:
        validate_mission(data, "m")
    assert any(message in p for p in err.value.problems)


def test_same_position_new_heading_is_not_a_duplicate():
    m = validate_mission({"waypoints": [[0, 0, 0], [0, 0, 90], [0, 0, 450.0 - 360.0 + 90]]}, "m")
    assert len(m.waypoints) == 3


def test_gait_library_is_checked(tmp_path):
    with pytest.raises(MissionError, match="gaits.turn_left \\(default\\): unknown gait 'turn_left'"):
        validate_mission({"waypoints": [[0, 0, 0]]}, "m",
                         gait_library=["sidewind", "turn_right", "near_turn_left", "near_turn_right", "hold"])


def test_cli_check_ok(capsys):
    assert cli_main(["mission", "check", str(MISSIONS_DIR / "star.yaml")]) == 0
    out = capsys.readouterr().out
    assert "mission 'star': 5 waypoint(s)" in out


def test_cli_check_bad_lists_every_problem(tmp_path, capsys):
    f = tmp_path / "bad.yaml"
    f.write_text(BAD)
    assert cli_main(["mission", "check", str(MISSIONS_DIR / "star.yaml"), str(f)]) == 1
    err = capsys.readouterr().err
    assert "10 problem(s)" in err and "waypoints[5][2] (heading_deg)" in err and "colour: unknown key" in err


def test_cli_entry_point_exit_code(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text("waypoints: [[0, 0]]\n")
    r = subprocess.run([sys.executable, "-m", "snake_autonomy.cli", "mission", "check", str(f)],
                       capture_output=True, text=True)
    assert r.returncode == 1
    assert "waypoints[0]: expected [x_m, y_m, heading_deg], got [0, 0]" in r.stderr
    r = subprocess.run([sys.executable, "-m", "snake_autonomy.cli", "mission", "check", str(tmp_path / "nope.yaml")],
                       capture_output=True, text=True)
    assert r.returncode == 1 and "file not found" in r.stderr


def test_sizes_and_physical_ranges(tmp_path):
    """Finite but absurd values and oversized lists are refused with key and value."""
    data = {"waypoints": [[1e308, 0, 0], [0, 1, 7200]], "time_limit_s": 1e12,
            "tracker": {"d_th_m": 1e9, "psi_wp_deg": 1e6, "kp": 1e300}}
    with pytest.raises(MissionError) as err:
        validate_mission(data, "absurd.yaml")
    text = str(err.value)
    for expected in ("waypoints[0][0] (x_m): must be within +-1000, got 1e+308",
                     "waypoints[1][2] (heading_deg): must be within +-360, got 7200",
                     "time_limit_s: must be a positive number of seconds up to 86400, got 1000000000000.0",
                     "tracker.d_th_m: must be within +-100, got 1000000000.0",
                     "tracker.psi_wp_deg: must be within +-360, got 1000000.0",
                     "tracker.kp: must be within +-1000, got 1e+300"):
        assert expected in text, text
    with pytest.raises(MissionError, match="waypoints: at most 1000 waypoints, got 1001"):
        validate_mission({"waypoints": [[i * 0.01, 0, 0] for i in range(1001)]}, "long.yaml")
    tracker = tmp_path / "tracker.yaml"
    tracker.write_text("rate_hz: 1.0e+9\npose_timeout_s: 2.0\nyaw_filter_window: 5\n")
    from snake_autonomy.missions import load_defaults
    with pytest.raises(MissionError, match="rate_hz: must be at most 1000 Hz, got 1000000000.0"):
        load_defaults(tracker)
    huge = {"waypoints": [[0, 0, 0]], "description": ["x" * 10] * 100000, "colour": "r" * 10 ** 6}
    with pytest.raises(MissionError) as err:
        validate_mission(huge, "huge.yaml")
    assert len(str(err.value)) < 1000      # values are cut short: the message stays readable
