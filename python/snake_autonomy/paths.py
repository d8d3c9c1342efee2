"""Where the package's data lives (config/, launch/, rviz/): the one place that knows.

In a clone or a catkin devel space the Python package is imported from the source tree
(python/snake_autonomy/), so the data sits two levels up. Once installed (`catkin config --install`)
the modules live in <prefix>/lib/python3/dist-packages/snake_autonomy/ and the data in
<prefix>/share/snake_autonomy/. Anything else (a package moved elsewhere on ROS_PACKAGE_PATH) is
asked of rospkg. SNAKE_AUTONOMY_ROOT (set by scripts/with-env) overrides all of them.
"""
import functools
import os
import re
from pathlib import Path

from .safe_yaml import short_repr

PACKAGE = "snake_autonomy"


def _is_package(path: Path) -> bool:
    return (path / "package.xml").is_file() and (path / "config").is_dir()


@functools.lru_cache(maxsize=None)
def package_root() -> Path:
    """The folder holding package.xml and config/ (source tree or install share directory)."""
    env = os.environ.get("SNAKE_AUTONOMY_ROOT")
    if env and _is_package(Path(env)):
        return Path(env)
    here = Path(__file__).resolve()
    source = here.parents[2]                       # <clone>/python/snake_autonomy/paths.py
    installed = here.parents[4] / "share" / PACKAGE  # <prefix>/lib/python3/dist-packages/snake_autonomy/paths.py
    for candidate in (source, installed):
        if _is_package(candidate):
            return candidate
    try:
        import rospkg  # lazy: ROS's package index, asked only when the data is in neither place

        return Path(rospkg.RosPack().get_path(PACKAGE))
    except Exception as exc:  # noqa: BLE001 - any failure means: not found
        raise FileNotFoundError(f"cannot find the {PACKAGE} package data: not in {source}, not in {installed}, "
                                f"not on ROS_PACKAGE_PATH (set SNAKE_AUTONOMY_ROOT)") from exc


def config_path(*parts: str) -> Path:
    """A path under the package's config/ (config_path() is config/ itself)."""
    return package_root().joinpath("config", *parts)


# The name of a provided file (config/<folder>/NAME.yaml): no path separator, no leading dot.
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")


class NotANameError(ValueError):
    """Neither a provided file's name nor a YAML file's path; `value` is quoted (short, escaped)."""

    def __init__(self, value: str, folder: str):
        self.value = short_repr(value)
        self.problem = (f"neither the name of a provided file ({folder}/NAME.yaml: NAME of letters, digits, "
                        f"_ . -) nor a file (a path ending in .yaml or .yml)")
        super().__init__(f"{self.value}: {self.problem}")


def named_yaml(folder: str, name_or_path: str) -> Path:
    """A YAML file given as a path ending in .yaml/.yml (taken as it is) or as the NAME of a provided
    one, which means config/<folder>/NAME.yaml and nothing else: a name never leaves its folder
    (../../etc/passwd is refused, NotANameError, before a byte is read)."""
    text = str(name_or_path)
    p = Path(os.path.expanduser(text))
    if p.suffix in (".yaml", ".yml"):
        return p
    if NAME.fullmatch(text):
        return config_path(folder, f"{text}.yaml")
    raise NotANameError(text, f"config/{folder}")


def robot_yaml(name_or_path: str) -> Path:
    """A robot description: a path ending in .yaml/.yml, or a name under config/robots/ ('cobra')."""
    return named_yaml("robots", name_or_path)


def resolve_world_path(path) -> Path:
    """A nav world file as an absolute path that exists: `~` expanded, a relative path taken against the
    process's working directory (the user's shell for a command or `rosrun`; ROS_HOME, ~/.ros, for a node
    roslaunch starts, which is why launch/sim.launch hands its nodes world:= made absolute against the shell's
    directory). FileNotFoundError names the path tried (and the working directory for a relative one);
    ValueError for an empty path (no world)."""
    text = str(path).strip()
    if not text:
        raise ValueError("world: empty path (no world file given)")
    given = Path(os.path.expanduser(text))
    resolved = given if given.is_absolute() else Path.cwd() / given
    if resolved.is_file():
        return resolved
    why = "is not a file" if resolved.exists() else "does not exist"
    if given.is_absolute():
        raise FileNotFoundError(f"world file {resolved} {why}")
    raise FileNotFoundError(f"world file {resolved} {why} (the relative path {text!r} taken against the working "
                            f"directory {Path.cwd()}; a node roslaunch starts runs in ROS_HOME, not in your shell's "
                            f"directory: give an absolute path, $(find snake_autonomy)/config/worlds/NAME.yaml, or "
                            f"launch through sim.launch, which makes world:= absolute)")


def default_results_dir() -> str:
    """Where runs record when no results_dir is given: the clone's results/ (scripts/with-env sets
    SNAKE_AUTONOMY_ROOT), else $ROS_HOME/snake_autonomy_results (ROS_HOME defaults to ~/.ros)."""
    root = os.environ.get("SNAKE_AUTONOMY_ROOT")
    if root:
        return os.path.join(root, "results")
    return os.path.join(os.environ.get("ROS_HOME", os.path.expanduser("~/.ros")), "snake_autonomy_results")
