"""Every `snake_autonomy` subcommand, as a process, on hostile input files: exit 1, the file or key
named in one message, never a traceback.

Before the bounded loaders each of these cases ended in a traceback (UnicodeDecodeError,
RecursionError, MemoryError after gigabytes, bad_alloc), was silently accepted (a duplicated key, a
1e308 mass written as mass="inf") or exited 0 (an evaluation with rmse inf).
"""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
COBRA = (ROOT / "config" / "robots" / "cobra.yaml").read_text()
MISSION = "name: m\nwaypoints:\n  - [1.0, 0.0, 0.0]\n"

BINARY = bytes(range(256)) * 8
UTF16 = MISSION.encode("utf-16")
BILLION_LAUGHS = ("a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
                  + "".join(f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
                            for p, c in zip("abcdefgh", "bcdefghi"))
                  + "waypoints: *i\n").encode()
DUPLICATE = (MISSION + "waypoints:\n  - [2.0, 0.0, 0.0]\n").encode()
DEEP = ("waypoints: " + "[" * 20000 + "]" * 20000 + "\n").encode()
HUGE_JOINTS = re.sub(r"num_joints: \d+", "num_joints: 1000000000", COBRA).encode()
HUGE_MASS = re.sub(r"masses_kg: \[.*\]", "masses_kg: [" + ", ".join(["1e308"] * 13) + "]", COBRA).encode()
TUM_1E308 = "".join(f"{1000 + 0.1 * k:.1f} {1e308 if k == 5 else k * 0.01} 0 0 0 0 0 1\n"
                    for k in range(20)).encode()
TUM_OK = "".join(f"{1000 + 0.1 * k:.1f} {k * 0.01} 0 0 0 0 0 1\n" for k in range(20)).encode()
MISSION_INPUTS = {"binary": (BINARY, "not a text file"), "utf16": (UTF16, "not UTF-8 text"),
                  "billion_laughs": (BILLION_LAUGHS, "anchor &a refused"),
                  "duplicate_key": (DUPLICATE, "line 4: duplicate key 'waypoints' (first given on line 2)"),
                  "deep_nesting": (DEEP, "nested deeper than 32 levels")}
ROBOT_INPUTS = {"binary": (BINARY, "not a text file"), "utf16": (COBRA.encode("utf-16"), "not a text file"),
                "huge_num_joints": (HUGE_JOINTS, "num_joints: must be an integer in 2..64, got 1000000000"),
                "huge_mass": (HUGE_MASS, "masses_kg[0]: must be at most 100 kg, got 1e+308"),
                "billion_laughs": (BILLION_LAUGHS, "more than 65536 values (aliases expanding?)"),
                "duplicate_key": ((COBRA + "num_joints: 12\n").encode(),
                                  ": duplicate key 'num_joints' (first given on line 5)")}


def run_cli(*args, timeout=120):
    """`python3 -m snake_autonomy.cli ARGS` (the console entry's code) with a 2 GB address-space cap,
    so that a loader without bounds fails fast instead of taking the machine's memory."""
    def cap():
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))
    return subprocess.run([sys.executable, "-m", "snake_autonomy.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, preexec_fn=cap, env={**os.environ, "MPLBACKEND": "Agg"})


def assert_refused(proc, *expected):
    assert "Traceback" not in proc.stderr + proc.stdout, proc.stderr[-2000:]
    assert proc.returncode == 1, (proc.returncode, proc.stdout[-500:], proc.stderr[-2000:])
    for text in expected:
        assert text in proc.stderr, (text, proc.stderr[-2000:])


def write(tmp_path, name, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("case", sorted(MISSION_INPUTS))
def test_mission_check(tmp_path, case):
    data, message = MISSION_INPUTS[case]
    f = write(tmp_path, f"{case}.yaml", data)
    assert_refused(run_cli("mission", "check", f), str(f), message)


@pytest.mark.parametrize("case", sorted(MISSION_INPUTS))
def test_mission_check_tracker_defaults(tmp_path, case):
    data, message = MISSION_INPUTS[case]
    f = write(tmp_path, f"{case}_tracker.yaml", data)
    assert_refused(run_cli("mission", "check", "star", "--defaults", f), str(f), message)


@pytest.mark.parametrize("case", sorted(MISSION_INPUTS))
def test_sim_run_mission(tmp_path, case):
    data, message = MISSION_INPUTS[case]
    f = write(tmp_path, f"{case}.yaml", data)
    assert_refused(run_cli("sim", "run", "--mission", f, "--out", tmp_path / "out", "--no-plots"), str(f), message)


@pytest.mark.parametrize("case", ["binary", "utf16", "duplicate_key"])
def test_sim_run_sim_config(tmp_path, case):
    data, message = MISSION_INPUTS[case]
    if case == "duplicate_key":
        data, message = b"physics:\n  timestep: 0.002\nphysics: {}\n", "line 3: duplicate key 'physics'"
    f = write(tmp_path, f"{case}_sim.yaml", data)
    assert_refused(run_cli("sim", "run", "--mission", "single_waypoint", "--sim-config", f, "--out",
                           tmp_path / "out", "--no-plots"), str(f), message)


@pytest.mark.parametrize("case", sorted(ROBOT_INPUTS))
def test_urdf(tmp_path, case):
    data, message = ROBOT_INPUTS[case]
    f = write(tmp_path, f"{case}_robot.yaml", data)
    proc = run_cli("urdf", f)
    assert_refused(proc, str(f), message)
    assert 'mass value="inf"' not in proc.stdout


@pytest.mark.parametrize("case", sorted(ROBOT_INPUTS))
def test_gait_robot(tmp_path, case):
    data, message = ROBOT_INPUTS[case]
    f = write(tmp_path, f"{case}_robot.yaml", data)
    assert_refused(run_cli("gait", "--robot", f, "--duration", "0.1", "--out", tmp_path / "out"), str(f), message)


def test_gait_library_out_of_range(tmp_path):
    text = (ROOT / "config" / "gaits.yaml").read_text().replace("frequency_hz: 0.35", "frequency_hz: 1.0e+308", 1)
    f = write(tmp_path, "gaits.yaml", text.encode())
    assert_refused(run_cli("gait", "--gaits", f, "--duration", "0.1", "--out", tmp_path / "out"), str(f),
                   "gaits.sidewind.frequency_hz: must be in 0..5 Hz, got 1e+308")


def test_evaluate_a_1e308_row(tmp_path):
    ref, est = write(tmp_path, "ref.txt", TUM_OK), write(tmp_path, "est.txt", TUM_1E308)
    assert_refused(run_cli("evaluate", ref, est), str(est), "pose 5", "beyond +-100000 m")


def test_evaluate_into_a_folder_that_cannot_be_created(tmp_path):
    ref = write(tmp_path, "ref.txt", TUM_OK)
    blocker = write(tmp_path, "file", b"x")
    assert_refused(run_cli("evaluate", ref, ref, "--plots", blocker / "plots"), "--plots", str(blocker / "plots"))
    assert_refused(run_cli("evaluate", ref, ref, "--json", blocker / "sub" / "out.json"), "--json")


@pytest.mark.parametrize("option,value,message", [
    ("--duration", "1e9", "--duration: must be at most 3600 s, got 1000000000.0"),
    ("--dt", "1e-9", "--duration / --dt: at most 1e6 steps"),
    ("--steer-deg", "inf", "--steer-deg: must be within +-90, got inf"),
])
def test_gait_options_have_ranges(tmp_path, option, value, message):
    assert_refused(run_cli("gait", option, value, "--out", tmp_path / "out"), message)


def test_outputs_into_a_folder_that_cannot_be_created(tmp_path):
    blocker = write(tmp_path, "file", b"x")
    assert_refused(run_cli("gait", "--duration", "0.1", "--out", blocker / "out"), "--out", str(blocker / "out"))
    assert_refused(run_cli("sim", "run", "--mission", "single_waypoint", "--time-limit", "inf", "--out",
                           tmp_path / "o"), "--time-limit: must be a number of seconds in (0, 86400], got inf")


@pytest.mark.parametrize("value", ["-5", "0", "nan", "inf"])
def test_nav_run_time_limit_must_be_positive_and_finite(tmp_path, value):
    proc = run_cli("nav", "run", "--world", ROOT / "config" / "worlds" / "corridor.yaml", "--time-limit", value,
                   "--out", tmp_path / "out")
    assert_refused(proc, "--time-limit: must be a finite number of seconds > 0, got")
    assert "UnboundLocalError" not in proc.stderr


def test_nav_run_refuses_a_world_wider_than_the_route_grid(tmp_path):
    """Both ends within the world bounds (+-100 m), but 180 m apart: the route grid would take
    gigabytes; refused before the simulator starts."""
    world = write(tmp_path, "wide.yaml", b"start: [-90.0, -90.0, 45.0]\ngoal: [90.0, 90.0]\ngoal_radius_m: 0.3\n"
                                         b"obstacles:\n  - {type: cylinder, x: -89.4, y: -89.4, radius_m: 0.1, "
                                         b"height_m: 0.3}\n")
    proc = run_cli("nav", "run", "--world", world, "--time-limit", "5", "--out", tmp_path / "out")
    assert_refused(proc, "route grid", "182.0 m x 182.0 m", "map.route_max_cells")


def test_nav_run_refuses_a_steering_law_the_loop_does_not_command(tmp_path):
    """follow_the_leader is a prototype of bench/nav_follow_the_leader: the navigation loop commands
    uniform curvature only, and says so before the simulator starts."""
    cfg = write(tmp_path, "ftl.yaml", b"base: " + str(ROOT / "config" / "nav.yaml").encode()
                + b"\ngaits: {steering: follow_the_leader}\n")
    proc = run_cli("nav", "run", "--world", ROOT / "config" / "worlds" / "corridor.yaml", "--config", cfg,
                   "--time-limit", "5", "--out", tmp_path / "out")
    assert_refused(proc, "gaits.steering: 'follow_the_leader'", "uniform")


@pytest.mark.parametrize("command", [("urdf",), ("gait", "--duration", "0.1", "--robot")])
def test_a_robot_name_resolves_only_inside_config_robots(tmp_path, command):
    """A name is config/robots/NAME.yaml and nothing else: ../../../../etc/passwd is not read."""
    proc = run_cli(*command, "../../../../etc/passwd", *(("--out", tmp_path / "out") if len(command) > 1 else ()))
    assert_refused(proc, "'../../../../etc/passwd': neither the name of a provided file (config/robots/NAME.yaml")


SCOUT_CONFIG_INPUTS = {"binary": (BINARY, "not a text file"), "utf16": (COBRA.encode("utf-16"), "not UTF-8 text"),
                       "billion_laughs": (BILLION_LAUGHS, "anchor &a refused"),
                       "nan_gain": (b"planner:\n  k1: .nan\n", "planner.k1: must be a finite number, got nan")}


@pytest.mark.parametrize("case", sorted(SCOUT_CONFIG_INPUTS))
def test_scout_config(tmp_path, case):
    data, message = SCOUT_CONFIG_INPUTS[case]
    path = write(tmp_path, "scout.yaml", data)
    proc = run_cli("scout", "plan", "--robot", "cobra", "--max-active", "2", "--config", path,
                   "--out", tmp_path / "out")
    assert_refused(proc, f"scout plan: {path}: ", message)
    assert len(proc.stderr.strip().splitlines()) == 1 and len(proc.stderr) < 500


@pytest.mark.parametrize("option", ["--seed", "--sim-seed"])
def test_scout_seeds_are_non_negative_integers(tmp_path, option):
    proc = run_cli("scout", "run", "--robot", "cobra", "--max-active", "2", option, "-1", "--out", tmp_path / "out")
    assert_refused(proc, f"scout run: {option} -1: must be an integer in 0..4294967295")
