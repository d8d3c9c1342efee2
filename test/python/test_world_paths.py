"""A nav world given as a relative path: paths.resolve_world_path (what sim_node does with ~world) and
launch/sim.launch, which makes world:= absolute against the user's shell directory (PWD) before any node
sees it (roslaunch starts nodes in ROS_HOME, so a relative path handed on would be looked for there).
The launch checks ask roslaunch itself (--dump-params: no master, nothing started)."""
import os
import subprocess
from pathlib import Path

import pytest
import yaml

from snake_autonomy.paths import resolve_world_path


@pytest.fixture
def world(tmp_path):
    (tmp_path / "sub").mkdir()
    path = tmp_path / "sub" / "w.yaml"
    path.write_text("start: [0, 0, 0]\ngoal: [1, 0]\n")
    return path


def test_a_relative_path_is_taken_against_the_working_directory(world, monkeypatch):
    monkeypatch.chdir(world.parent.parent)
    assert resolve_world_path("sub/w.yaml") == world
    assert resolve_world_path("./sub/../sub/w.yaml").resolve() == world
    assert resolve_world_path(str(world)) == world              # absolute: as it is


def test_home_is_expanded(world, monkeypatch):
    monkeypatch.setenv("HOME", str(world.parent.parent))
    assert resolve_world_path("~/sub/w.yaml") == world


def test_a_missing_world_names_the_path_tried_and_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(FileNotFoundError) as e:
        resolve_world_path("worlds/nope.yaml")
    msg = str(e.value)
    assert str(tmp_path / "worlds" / "nope.yaml") in msg and "does not exist" in msg
    assert f"working directory {tmp_path}" in msg and "ROS_HOME" in msg
    with pytest.raises(FileNotFoundError, match=f"world file {tmp_path / 'abs.yaml'} does not exist"):
        resolve_world_path(tmp_path / "abs.yaml")
    with pytest.raises(FileNotFoundError, match="is not a file"):
        resolve_world_path(str(tmp_path))
    with pytest.raises(ValueError, match="empty"):
        resolve_world_path(" ")


def _world_params(cwd: Path, world: str, **env_over):
    env = dict(os.environ, PWD=str(cwd), **env_over)
    r = subprocess.run(["roslaunch", "--dump-params", "snake_autonomy", "sim.launch", f"world:={world}"],
                       cwd=cwd, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    params = yaml.safe_load(r.stdout)
    return params.get("/sim/world"), params.get("/planner/world")


def test_sim_launch_makes_a_relative_world_absolute_against_the_shell_directory(world):
    cwd = world.parent.parent
    assert _world_params(cwd, "sub/w.yaml") == (str(world), str(world))
    assert _world_params(cwd, str(world)) == (str(world), str(world))
    assert _world_params(cwd, "~/w.yaml", HOME=str(world.parent)) == (str(world), str(world))
    assert _world_params(cwd, "") == (None, None)               # no world: the mission run, no planner
    assert _world_params(cwd, "none") == (None, None)


def test_a_world_name_is_the_packages_world_as_a_mission_name_is(root, world):
    """world:=NAME (no '/', no .yaml suffix) is config/worlds/NAME.yaml of the package, from any directory;
    a file name with its suffix stays a file of the shell's directory."""
    cwd = world.parent
    sim_world, planner_world = _world_params(cwd, "one_obstacle")
    assert sim_world == planner_world
    assert os.path.samefile(sim_world, root / "config" / "worlds" / "one_obstacle.yaml")
    assert _world_params(cwd, "w.yaml") == (str(world), str(world))


def test_bringup_resolves_world_as_sim_launch_does(root, world):
    env = dict(os.environ, PWD=str(world.parent.parent), SNAKE_AUTONOMY_ROOT=str(root))
    args = ("bus:=sim", "camera:=sim", "odometry:=sim")

    def dump(w):
        r = subprocess.run(["roslaunch", "--dump-params", "snake_autonomy", "bringup.launch", *args, f"world:={w}"],
                           cwd=world.parent.parent, env=env, capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stdout + r.stderr
        params = yaml.safe_load(r.stdout)
        assert params.get("/sim/world") == params.get("/planner/world")
        return params.get("/sim/world")

    assert os.path.samefile(dump("corridor"), root / "config" / "worlds" / "corridor.yaml")
    assert dump("sub/w.yaml") == str(world)
    assert dump("none") is None
