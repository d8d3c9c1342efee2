"""The package as ROS users deploy it and build on it: a release install, not the clone.

One scratch catkin workspace in a temporary folder (src/ symlinks this clone and the downstream
package test/downstream), built once with `catkin config --install` (the C++ tests and benchmarks
left out), then everything below runs from its install space with the clone out of the
environment (no devel space, no SNAKE_AUTONOMY_ROOT, no source tree on PYTHONPATH):

- the Python package, the bindings and the data (config/) come from the install space;
- every node and script is installed where rosrun and roslaunch look;
- the CLI: `snake_autonomy mission check star`, --help of every subcommand, the URDF;
- the downstream package compiled and linked against the installed core, and its FK binary runs;
- `roslaunch snake_autonomy driver.launch mock:=true` and `sim.launch` (every node of the stack)
  start, and the driver publishes joint_states over the (mocked, simulated) servo bus.

Run by scripts/run_tests (suite "install"). About 1-3 min of build on two cores; set
SNAKE_KEEP_INSTALL_WS=1 to keep the scratch workspace for a look, SNAKE_INSTALL_WS=DIR to run the
tests again on a kept one without building.
"""
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from snake_autonomy.cli import SUBCOMMANDS

ROOT = Path(__file__).resolve().parents[2]
PKG = "snake_autonomy"
NODES = ("driver_node", "sim_node", "mission_node", "planner_node", "nav_record_node", "pose_remap_node", "viz_node",
         "mock_servo_bus_node")
SCRIPTS = ("snake_autonomy", "evaluate", "mock_servo_bus")
NESTED_SUBCOMMANDS = [["mission", "check"], ["mission", "list"], ["sim", "run"], ["sim", "experiment"]]
BUILD_TIMEOUT_S = 1500


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _venv() -> Path:
    env = os.environ.get("VIRTUAL_ENV")
    return Path(env) if env else ROOT / ".venv"


def _clean_env(tmp: Path) -> dict:
    """The machine's environment without anything of the clone's workspace."""
    drop = ("ROS_", "CMAKE_PREFIX_PATH", "PYTHONPATH", "LD_LIBRARY_PATH", "PKG_CONFIG_PATH", "SNAKE_AUTONOMY",
            "CATKIN", "ROSLISP", "PYTEST")
    env = {k: v for k, v in os.environ.items() if not k.startswith(drop)}
    env["PATH"] = f"{_venv() / 'bin'}:/usr/local/sbin:/usr/sbin:/usr/bin:/sbin:/bin"
    env["VIRTUAL_ENV"] = str(_venv())
    env["ROS_HOME"] = str(tmp / "ros_home")
    env["MPLBACKEND"] = "Agg"
    return env


class Workspace:
    def __init__(self, root: Path, env: dict):
        self.root = root
        self.install = root / "install"
        self.env = env

    def run(self, cmd, timeout=120, **kw):
        return subprocess.run(cmd, env=self.env, cwd=self.root, capture_output=True, text=True, timeout=timeout,
                              **kw)


def _sourced_env(setup: Path, base: dict) -> dict:
    out = subprocess.run(["bash", "-c", f"set --; source '{setup}' && env -0"], env=base, capture_output=True,
                         check=True, timeout=60).stdout
    return dict(item.split("=", 1) for item in out.decode().split("\0") if "=" in item)


@pytest.fixture(scope="module")
def ws():
    if shutil.which("catkin", path=_clean_env(Path("/tmp"))["PATH"]) is None:
        pytest.fail("catkin (catkin-tools) is not installed: run scripts/bootstrap")
    reuse = os.environ.get("SNAKE_INSTALL_WS")   # a workspace this test built before (SNAKE_KEEP_INSTALL_WS)
    if reuse:
        w = Workspace(Path(reuse), _clean_env(Path(reuse)))
        w.env = _sourced_env(w.install / "setup.bash", w.env)
        w.env["ROS_MASTER_URI"] = f"http://127.0.0.1:{_free_port()}"
        yield w
        return
    # Not pytest's tmp_path: other pytest sessions of the same user prune those folders.
    root = Path(tempfile.mkdtemp(prefix="snake_install_ws_"))
    (root / "src").mkdir()
    (root / "src" / PKG).symlink_to(ROOT)
    (root / "src" / "snake_autonomy_downstream").symlink_to(ROOT / "test" / "downstream")
    env = _clean_env(root)
    python = _venv() / "bin" / "python3"
    steps = [["catkin", "init"],
             ["catkin", "config", "--install", "--cmake-args", "-DCMAKE_BUILD_TYPE=Release",
              f"-DPYTHON_EXECUTABLE={python}", "-DCATKIN_ENABLE_TESTING=OFF", f"-D{PKG}_BUILD_TESTS=OFF"],
             ["catkin", "build", "--no-status", "--no-notify", "-j2"]]
    t0 = time.monotonic()
    for cmd in steps:
        r = subprocess.run(cmd, cwd=root, env=env, capture_output=True, text=True, timeout=BUILD_TIMEOUT_S)
        if r.returncode != 0:
            pytest.fail(f"{' '.join(cmd)} failed ({r.returncode}):\n{(r.stdout + r.stderr)[-6000:]}")
    print(f"scratch install workspace built in {time.monotonic() - t0:.0f} s: {root}")
    w = Workspace(root, env)
    w.env = _sourced_env(w.install / "setup.bash", env)
    w.env["ROS_MASTER_URI"] = f"http://127.0.0.1:{_free_port()}"
    yield w
    if not os.environ.get("SNAKE_KEEP_INSTALL_WS"):
        shutil.rmtree(root, ignore_errors=True)


def test_python_package_bindings_and_data_come_from_the_install_space(ws):
    r = ws.run([sys.executable, "-c",
                "import snake_autonomy, snake_autonomy._core as c, snake_autonomy.msg as m\n"
                "from snake_autonomy.paths import package_root\n"
                "print(snake_autonomy.__file__); print(c.__file__); print(m.__file__); print(package_root())"])
    assert r.returncode == 0, r.stderr
    module, core, msg, root = r.stdout.split()
    for path in (module, core, msg):
        assert Path(path).is_relative_to(ws.install), f"{path} is not in the install space {ws.install}"
    assert Path(root) == ws.install / "share" / PKG


def test_every_node_and_script_is_installed_where_rosrun_looks(ws):
    for name in NODES + SCRIPTS:
        r = ws.run(["catkin_find", "--without-underlays", "--libexec", PKG, name])
        found = [Path(p) for p in r.stdout.split()]
        assert found and all(p.is_relative_to(ws.install) for p in found), f"{name}: {r.stdout}{r.stderr}"
        assert os.access(found[0], os.X_OK), found[0]


@pytest.mark.parametrize("script", ["mock_servo_bus", "mock_servo_bus_node", "evaluate"])
def test_rosrun_help(ws, script):
    r = ws.run(["rosrun", PKG, script, "--help"])
    assert r.returncode == 0, r.stdout + r.stderr
    assert "usage:" in r.stdout


def test_cli_checks_the_provided_star_mission(ws):
    r = ws.run(["snake_autonomy", "mission", "check", "star"])
    assert r.returncode == 0, r.stdout + r.stderr
    assert "star" in r.stdout


def test_cli_every_subcommand_has_help(ws):
    r = ws.run(["snake_autonomy", "--help"])
    assert r.returncode == 0, r.stderr
    assert all(command in r.stdout for command in SUBCOMMANDS)
    for command in [[c] for c in SUBCOMMANDS] + NESTED_SUBCOMMANDS:
        r = ws.run(["snake_autonomy", *command, "--help"])
        assert r.returncode == 0 and "usage:" in r.stdout, f"{command} --help: {r.stdout}{r.stderr}"


def test_installed_urdf_passes_check_urdf(ws, tmp_path):
    r = ws.run(["snake_autonomy", "urdf", "cobra"])
    assert r.returncode == 0, r.stderr
    urdf = tmp_path / "cobra.urdf"
    urdf.write_text(r.stdout)
    check = ws.run(["check_urdf", str(urdf)])
    assert check.returncode == 0, check.stdout + check.stderr
    assert "camera_color_optical_frame" in check.stdout


def test_downstream_package_builds_against_the_installed_core_and_runs_fk(ws):
    binary = ws.install / "lib" / "snake_autonomy_downstream" / "fk_demo"
    assert binary.is_file(), f"{binary} missing: the downstream package did not build"
    r = ws.run([str(binary), str(ws.install / "share" / PKG / "config" / "robots" / "cobra.yaml")])
    assert r.returncode == 0, r.stdout + r.stderr
    fields = dict(kv.split("=") for kv in r.stdout.split())
    assert int(fields["frames"]) == 13
    assert float(fields["tail_x"]) == pytest.approx(-(0.1565 + 11 * 0.1230), abs=1e-9)


def _launch_until_joint_states(ws, args, expect_nodes, also_topics=(), timeout_s=120.0):
    """roslaunch from the install space until the driver publishes joint_states; then stops it."""
    log = open(ws.root / f"roslaunch_{args[0]}.log", "w")
    port = ws.env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = subprocess.Popen(["roslaunch", "-p", port, PKG, *args], env=ws.env, cwd=ws.root, stdout=log,
                            stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + timeout_s
        echo = None
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                log.flush()
                tail = "".join(Path(log.name).read_text(errors="replace").splitlines(True)[-40:])
                pytest.fail(f"roslaunch exited {proc.returncode}; the end of {log.name}:\n{tail}")
            try:
                echo = ws.run(["rostopic", "echo", "-n", "1", "--noarr", "/joint_states"], timeout=15)
            except subprocess.TimeoutExpired:
                continue
            if echo.returncode == 0 and "header" in echo.stdout:
                break
            time.sleep(1.0)
        else:
            pytest.fail(f"no /joint_states within {timeout_s} s: see {log.name}")
        nodes = ws.run(["rosnode", "list"]).stdout.split()
        missing = [n for n in expect_nodes if f"/{n}" not in nodes]
        assert not missing, f"nodes not running: {missing} (running: {nodes})"
        description = ws.run(["rosparam", "get", "/robot_description"]).stdout
        assert "<robot name=" in description and "camera_link" in description
        for topic in also_topics:
            r = ws.run(["rostopic", "echo", "-n", "1", "--noarr", topic], timeout=30)
            assert r.returncode == 0 and r.stdout.strip(), f"nothing on {topic}: {r.stderr}"
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        log.close()


def test_driver_launch_with_the_mocked_bus(ws):
    # mock_servo_bus_node is a plain process (no ROS node): joint_states prove it answers the driver.
    _launch_until_joint_states(ws, ["driver.launch", "mock:=true", f"port:={ws.root / 'mock_bus'}"],
                               ["driver", "robot_state_publisher"])


def test_sim_launch_starts_the_simulated_robot(ws):
    _launch_until_joint_states(
        ws, ["sim.launch", "feedback:=vio", "auto_start:=false", f"port:={ws.root / 'sim_bus'}",
             f"results_dir:={ws.root / 'results'}"],
        ["sim", "driver", "pose_remapper", "mission", "snake_viz", "robot_state_publisher"], also_topics=["/clock"])
