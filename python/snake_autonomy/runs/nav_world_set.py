"""The worlds a navigation experiment runs on: a generated family's worlds K..K+N-1 sized for the robot,
or the user's own world files. `nav experiment`, `nav worlds`, `nav ros-experiment` and
bench/nav_world_paths all take their worlds from here, so each gets the same worlds for the same options.

    pairs = generated_worlds("barn", first_world=100, worlds=20, robot="cobra")   # [(World, BarnLayout)]
    worlds = world_files("my_worlds/*.yaml")                                       # [World], sorted

Errors are ValueError; their messages name the command-line options the callers share (--worlds,
--first-world) or the glob and file.
"""
import glob
from pathlib import Path
from typing import List, Optional, Tuple

from snake_autonomy import _core
from snake_autonomy.paths import robot_yaml
from snake_autonomy.planning.rectilinear.config import NavConfig, head_width_m, nav_config_path
from snake_autonomy.sim.nav_worlds import BarnLayout, barn_layout, random_corridor
from snake_autonomy.sim.world_file import World, WorldError, load_world


def generated_worlds(family: str, first_world: int, worlds: int,
                     robot: str) -> List[Tuple[World, Optional[BarnLayout]]]:
    """[(world, BarnLayout or None)] of the family's worlds first_world .. first_world + worlds - 1,
    for the robot: corridors' gaps from its body width, barn's footprint from the robot's own nav
    config's sampler.body_clearance_m (config/nav_ROBOT.yaml, else nav.yaml: never a --config being
    tuned, whose worlds would then change with it) and the body's length behind base_link from the
    robot model."""
    if worlds < 1:
        raise ValueError(f"--worlds must be >= 1, got {worlds}")
    if first_world < 0:
        raise ValueError(f"--first-world must be >= 0, got {first_world}")
    indices = range(first_world, first_world + worlds)
    ry = robot_yaml(robot)
    model = _core.RobotModel.from_yaml(str(ry))
    if family == "corridors":
        body = max(head_width_m(ry), 2.0 * model.link_radius_m)
        return [(random_corridor(k, body_width_m=body), None) for k in indices]
    clearance = NavConfig.from_yaml(nav_config_path(robot)).sampler.body_clearance_m
    length = model.head_length_m + model.num_joints * model.link_length_m + model.link_radius_m
    layouts = [barn_layout(k, clearance, body_length_m=length) for k in indices]
    return [(b.world, b) for b in layouts]


def world_files(pattern: str) -> List[World]:
    """The world files matching the glob, sorted, each named (its name, else its file's stem);
    ValueError naming the glob or the file, or the names more than one file carries (runs.csv
    and DIR/worlds/NAME.yaml are keyed by name)."""
    files = sorted(glob.glob(pattern, recursive=True))
    if not files:
        raise ValueError(f"no file matches {pattern!r}")
    loaded = []
    for f in files:
        try:
            w = load_world(f)
        except WorldError as e:
            raise ValueError(str(e)) from None
        w.name = w.name or Path(f).stem
        loaded.append(w)
    names = [w.name for w in loaded]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"world names must differ (runs.csv and DIR/worlds/NAME.yaml use them); more than one "
                         f"file is named {', '.join(twice)}: {', '.join(w.source for w in loaded if w.name in twice)}")
    return loaded
