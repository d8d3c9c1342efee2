"""The worlds of a navigation experiment (runs/nav_world_set.py): a generated family sized for the robot, or
world files; and bench/ scripts take them from there, not from the CLI's private helpers."""
import ast

import pytest
import yaml

from snake_autonomy._core import RobotModel
from snake_autonomy.paths import robot_yaml
from snake_autonomy.planning.rectilinear.config import head_width_m
from snake_autonomy.runs.nav_world_set import generated_worlds, world_files
from snake_autonomy.sim.nav_worlds import barn_world, random_corridor


def body_length_m(robot):
    m = RobotModel.from_yaml(str(robot_yaml(robot)))
    return m.head_length_m + m.num_joints * m.link_length_m + m.link_radius_m


def test_barn_worlds_are_the_family_sized_by_the_robots_nav_config_and_length():
    pairs = generated_worlds("barn", first_world=100, worlds=2, robot="chang_rectilinear")
    assert [w.name for w, _ in pairs] == ["barn_100", "barn_101"]
    assert all(layout is not None and layout.world is w for w, layout in pairs)
    # config/nav_chang_rectilinear.yaml: sampler.body_clearance_m 0.15
    expected = barn_world(100, 0.15, body_length_m=body_length_m("chang_rectilinear"))
    assert pairs[0][0].to_dict() == expected.to_dict()


def test_a_nav_config_being_tuned_does_not_change_the_generated_worlds(tmp_path):
    """An experiment's --config (here a footprint half the robot's) plans differently on the same worlds."""
    from snake_autonomy.cli import main as cli_main
    from snake_autonomy.paths import config_path
    overlay = tmp_path / "narrow.yaml"
    overlay.write_text(f"base: {config_path('nav.yaml')}\nsampler:\n  body_clearance_m: 0.125\n")
    out = tmp_path / "exp"
    assert cli_main(["nav", "experiment", "--family", "barn", "--first-world", "100", "--worlds", "1",
                     "--seeds", "0", "--time-limit", "1", "--engine", "serial", "--no-progress",
                     "--config", str(overlay), "--out", str(out)]) == 0
    written = yaml.safe_load((out / "worlds" / "barn_100.yaml").read_text())
    expected = barn_world(100, 0.25, body_length_m=body_length_m("cobra"))     # config/nav.yaml's 0.25
    assert written == yaml.safe_load(yaml.safe_dump(expected.to_dict(), sort_keys=False))


def test_corridors_have_gaps_from_the_robots_body_width():
    ry = robot_yaml("cobra")
    body = max(head_width_m(ry), 2.0 * RobotModel.from_yaml(str(ry)).link_radius_m)
    pairs = generated_worlds("corridors", first_world=3, worlds=2, robot="cobra")
    assert [layout for _, layout in pairs] == [None, None]
    assert [w.to_dict() for w, _ in pairs] == [random_corridor(k, body_width_m=body).to_dict() for k in (3, 4)]


@pytest.mark.parametrize("first,count,message", [(0, 0, "--worlds must be >= 1, got 0"),
                                                  (-1, 2, "--first-world must be >= 0, got -1")])
def test_a_bad_index_range_is_a_value_error_naming_the_option(first, count, message):
    with pytest.raises(ValueError, match=message):
        generated_worlds("barn", first_world=first, worlds=count, robot="cobra")


def write_world(path, name=None):
    data = {"start": [0, 0, 0], "goal": [1, 0], "goal_radius_m": 0.1}
    if name:
        data["name"] = name
    path.write_text(yaml.safe_dump(data))


def test_world_files_are_sorted_and_named_by_their_stem_when_unnamed(tmp_path):
    write_world(tmp_path / "b.yaml")
    write_world(tmp_path / "a.yaml", name="first")
    assert [w.name for w in world_files(str(tmp_path / "*.yaml"))] == ["first", "b"]


def test_world_files_matching_nothing_or_sharing_a_name_are_value_errors(tmp_path):
    with pytest.raises(ValueError, match="no file matches"):
        world_files(str(tmp_path / "*.yaml"))
    write_world(tmp_path / "a.yaml", name="same")
    write_world(tmp_path / "b.yaml", name="same")
    with pytest.raises(ValueError, match="more than one file is named same"):
        world_files(str(tmp_path / "*.yaml"))


def test_bench_scripts_import_no_private_name_of_the_package(root):
    """A bench script uses the package's public API (the compiled _core module aside): a private helper
    may change or vanish with its module."""
    private = []
    for script in sorted((root / "bench").iterdir()):
        if script.suffix or not script.is_file() or "python" not in script.read_text().partition("\n")[0]:
            continue
        for node in ast.walk(ast.parse(script.read_text(), str(script))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("snake_autonomy"):
                private += [f"{script.name}: {node.module}.{a.name}" for a in node.names
                            if a.name.startswith("_") and a.name != "_core"]
    assert private == []
