"""World files of the navigation experiment (issue 13): loading and validation, ROS-free.

A world is a YAML file::

    start: [x_m, y_m, heading_deg]      # base_link on the floor, heading CCW from +x
    goal: [x_m, y_m]
    goal_radius_m: 0.3
    obstacles:
      - {type: cylinder, x: 1.0, y: 0.2, radius_m: 0.1, height_m: 0.3}
      - {type: box, x: 2.0, y: -0.3, size_m: [0.2, 0.4, 0.3], yaw_deg: 30}
    floor_texture: carpet               # optional: one of FLOOR_TEXTURES (sim/scene.py)

Optional keys ``name`` and ``description``. A bad world is refused whole with every problem listed
(WorldError), each naming the key and the value, as mission files are.
"""
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, Optional, Sequence, Tuple

from ..safe_yaml import YamlFileError, load_yaml_file

#: Floor appearances a world may ask for (the textures themselves: sim/scene.py).
FLOOR_TEXTURES = ("plain", "checker", "carpet", "tiles", "concrete")
WORLD_KEYS = ("name", "description", "start", "goal", "goal_radius_m", "obstacles", "floor_texture")
CYLINDER_KEYS = ("type", "x", "y", "radius_m", "height_m")
BOX_KEYS = ("type", "x", "y", "size_m", "yaw_deg")


class WorldError(ValueError):
    """A world file that cannot be used; ``problems`` lists every reason."""

    def __init__(self, source: str, problems: Sequence[str]):
        self.source = source
        self.problems = list(problems)
        super().__init__(f"{source}: {len(self.problems)} problem(s):\n  " + "\n  ".join(self.problems))


@dataclass(frozen=True)
class Obstacle:
    """A cylinder (radius_m, height_m) or a box (size_m full edge lengths, yaw_deg) on the floor."""
    kind: str                     # "cylinder" or "box"
    x_m: float
    y_m: float
    radius_m: float = 0.0
    height_m: float = 0.0
    size_m: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_deg: float = 0.0

    @property
    def top_m(self) -> float:
        return self.height_m if self.kind == "cylinder" else self.size_m[2]

    def footprint_radius_m(self) -> float:
        """Radius of the smallest circle around the obstacle's footprint."""
        if self.kind == "cylinder":
            return self.radius_m
        return 0.5 * math.hypot(self.size_m[0], self.size_m[1])

    def corners(self) -> List[Tuple[float, float]]:
        """A box's footprint corners on the floor (counter-clockwise); a cylinder: none."""
        if self.kind == "cylinder":
            return []
        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        hx, hy = 0.5 * self.size_m[0], 0.5 * self.size_m[1]
        return [(self.x_m + c * x - s * y, self.y_m + s * x + c * y)
                for x, y in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]

    def distance_m(self, x_m: float, y_m: float) -> float:
        """Distance in the floor plane from a point to the footprint (0 inside)."""
        dx, dy = x_m - self.x_m, y_m - self.y_m
        if self.kind == "cylinder":
            return max(0.0, math.hypot(dx, dy) - self.radius_m)
        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        ex = max(0.0, abs(lx) - 0.5 * self.size_m[0])
        ey = max(0.0, abs(ly) - 0.5 * self.size_m[1])
        return math.hypot(ex, ey)


@dataclass
class World:
    start: Tuple[float, float, float]          # x_m, y_m, heading_deg as written
    goal: Tuple[float, float]
    goal_radius_m: float
    obstacles: List[Obstacle] = field(default_factory=list)
    floor_texture: str = "plain"
    name: str = ""
    description: str = ""
    source: str = ""

    @property
    def start_rad(self) -> Tuple[float, float, float]:
        """(x_m, y_m, heading_rad): what Plant's start takes."""
        return (self.start[0], self.start[1], math.radians(self.start[2]))

    def goal_reached(self, x_m: float, y_m: float) -> bool:
        return math.hypot(x_m - self.goal[0], y_m - self.goal[1]) <= self.goal_radius_m

    @classmethod
    def from_dict(cls, data: Any, source: str = "world") -> "World":
        problems: List[str] = []
        if not isinstance(data, dict):
            raise WorldError(source, [f"expected a mapping with start, goal, goal_radius_m, "
                                      f"obstacles; got {data!r}"])
        for key in data:
            if key not in WORLD_KEYS:
                problems.append(f"{key}: unknown key (value {data[key]!r}); known: {', '.join(WORLD_KEYS)}")
        start = _numbers(data, "start", 3, problems)
        goal = _numbers(data, "goal", 2, problems)
        radius = data.get("goal_radius_m")
        if "goal_radius_m" not in data:
            problems.append("goal_radius_m: missing (a distance > 0 in metres)")
        elif not _finite(radius) or radius <= 0:
            problems.append(f"goal_radius_m: must be a number > 0, got {radius!r}")
        raw_obstacles = data.get("obstacles", [])
        obstacles: List[Obstacle] = []
        if raw_obstacles is None:
            raw_obstacles = []
        if not isinstance(raw_obstacles, list):
            problems.append(f"obstacles: expected a list, got {raw_obstacles!r}")
            raw_obstacles = []
        for i, item in enumerate(raw_obstacles):
            ob = _obstacle(item, f"obstacles[{i}]", problems)
            if ob is not None:
                obstacles.append(ob)
        floor = data.get("floor_texture", "plain")
        if floor not in FLOOR_TEXTURES:
            problems.append(f"floor_texture: unknown texture {floor!r}; known: {', '.join(FLOOR_TEXTURES)}")
        if start and goal and not problems:
            for i, ob in enumerate(obstacles):
                if ob.distance_m(start[0], start[1]) <= 0.0:
                    problems.append(f"obstacles[{i}]: covers the start {list(start[:2])}")
                if ob.distance_m(goal[0], goal[1]) <= 0.0:
                    problems.append(f"obstacles[{i}]: covers the goal {list(goal)}")
        if problems:
            raise WorldError(source, problems)
        return cls(start=tuple(start), goal=tuple(goal), goal_radius_m=float(radius),
                   obstacles=obstacles, floor_texture=floor, name=str(data.get("name", "")),
                   description=str(data.get("description", "")), source=source)

    def to_dict(self) -> dict:
        """The world as its YAML mapping (for run logs and generated worlds)."""
        obs = []
        for ob in self.obstacles:
            if ob.kind == "cylinder":
                obs.append({"type": "cylinder", "x": ob.x_m, "y": ob.y_m,
                            "radius_m": ob.radius_m, "height_m": ob.height_m})
            else:
                obs.append({"type": "box", "x": ob.x_m, "y": ob.y_m,
                            "size_m": list(ob.size_m), "yaw_deg": ob.yaw_deg})
        out = {"start": list(self.start), "goal": list(self.goal),
               "goal_radius_m": self.goal_radius_m, "obstacles": obs,
               "floor_texture": self.floor_texture}
        if self.name:
            out["name"] = self.name
        return out


def load_world(path) -> World:
    path = Path(path)
    try:
        data = load_yaml_file(path)
    except (OSError, YamlFileError) as exc:
        raise WorldError(str(path), [f"cannot read: {exc}"]) from exc
    return World.from_dict(data, str(path))


def _finite(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _numbers(data: dict, key: str, n: int, problems: List[str]) -> Optional[List[float]]:
    v = data.get(key)
    if key not in data:
        problems.append(f"{key}: missing (a list of {n} numbers)")
        return None
    if not isinstance(v, list) or len(v) != n or not all(_finite(x) for x in v):
        problems.append(f"{key}: expected a list of {n} finite numbers, got {v!r}")
        return None
    return [float(x) for x in v]


def _positive(item: dict, key: str, where: str, problems: List[str]) -> float:
    v = item.get(key)
    if key not in item:
        problems.append(f"{where}.{key}: missing (a number > 0)")
    elif not _finite(v) or v <= 0:
        problems.append(f"{where}.{key}: must be a number > 0, got {v!r}")
    else:
        return float(v)
    return 0.0


def _obstacle(item: Any, where: str, problems: List[str]) -> Optional[Obstacle]:
    if not isinstance(item, dict):
        problems.append(f"{where}: expected a mapping with type cylinder or box, got {item!r}")
        return None
    kind = item.get("type")
    if kind not in ("cylinder", "box"):
        problems.append(f"{where}.type: must be cylinder or box, got {kind!r}")
        return None
    keys = CYLINDER_KEYS if kind == "cylinder" else BOX_KEYS
    before = len(problems)
    for key in item:
        if key not in keys:
            problems.append(f"{where}.{key}: unknown key for a {kind} (value {item[key]!r}); "
                            f"known: {', '.join(keys)}")
    xy = []
    for key in ("x", "y"):
        if not _finite(item.get(key)):
            problems.append(f"{where}.{key}: must be a finite number (m), got {item.get(key)!r}")
        else:
            xy.append(float(item[key]))
    if kind == "cylinder":
        radius = _positive(item, "radius_m", where, problems)
        height = _positive(item, "height_m", where, problems)
        if len(problems) > before:
            return None
        return Obstacle("cylinder", xy[0], xy[1], radius_m=radius, height_m=height)
    size = item.get("size_m")
    if not isinstance(size, list) or len(size) != 3 or not all(_finite(s) and s > 0 for s in size):
        problems.append(f"{where}.size_m: expected [sx, sy, sz], three numbers > 0 (m), got {size!r}")
    yaw = item.get("yaw_deg", 0.0)
    if not _finite(yaw):
        problems.append(f"{where}.yaw_deg: must be a finite number (deg), got {yaw!r}")
    if len(problems) > before:
        return None
    return Obstacle("box", xy[0], xy[1], size_m=tuple(float(s) for s in size), yaw_deg=float(yaw))
