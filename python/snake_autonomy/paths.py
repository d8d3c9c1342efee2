"""Where the package's data lives (config/, launch/, urdf/): the source tree in a catkin devel
space or a clone, the share directory once installed."""
import os
from pathlib import Path


def package_root() -> Path:
    env = os.environ.get("SNAKE_AUTONOMY_ROOT")
    if env and (Path(env) / "package.xml").is_file():
        return Path(env)
    here = Path(__file__).resolve().parents[2]  # python/snake_autonomy/paths.py -> repo root
    if (here / "package.xml").is_file():
        return here
    try:
        import rospkg

        return Path(rospkg.RosPack().get_path("snake_autonomy"))
    except Exception as exc:  # noqa: BLE001 - any failure means: not found
        raise FileNotFoundError("cannot find the snake_autonomy package (set SNAKE_AUTONOMY_ROOT)") from exc


def config_path(*parts: str) -> Path:
    return package_root().joinpath("config", *parts)


def robot_yaml(name_or_path: str) -> Path:
    """A robot description: a path, or a name under config/robots/ ('cobra')."""
    p = Path(name_or_path)
    if p.suffix in (".yaml", ".yml") or p.exists():
        return p
    return config_path("robots", f"{name_or_path}.yaml")
