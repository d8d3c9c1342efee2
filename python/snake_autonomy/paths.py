"""Where the package's data lives (config/, launch/, rviz/): the one place that knows.

In a clone or a catkin devel space the Python package is imported from the source tree
(python/snake_autonomy/), so the data sits two levels up. Once installed (`catkin config --install`)
the modules live in <prefix>/lib/python3/dist-packages/snake_autonomy/ and the data in
<prefix>/share/snake_autonomy/. Anything else (a package moved elsewhere on ROS_PACKAGE_PATH) is
asked of rospkg. SNAKE_AUTONOMY_ROOT (set by scripts/with-env) overrides all of them.
"""
import functools
import os
from pathlib import Path

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
        import rospkg

        return Path(rospkg.RosPack().get_path(PACKAGE))
    except Exception as exc:  # noqa: BLE001 - any failure means: not found
        raise FileNotFoundError(f"cannot find the {PACKAGE} package data: not in {source}, not in {installed}, "
                                f"not on ROS_PACKAGE_PATH (set SNAKE_AUTONOMY_ROOT)") from exc


def config_path(*parts: str) -> Path:
    """A path under the package's config/ (config_path() is config/ itself)."""
    return package_root().joinpath("config", *parts)


def robot_yaml(name_or_path: str) -> Path:
    """A robot description: a path, or a name under config/robots/ ('cobra')."""
    p = Path(name_or_path)
    if p.suffix in (".yaml", ".yml") or p.exists():
        return p
    return config_path("robots", f"{name_or_path}.yaml")
