"""World files of the navigation experiment: loading and validation, ROS-free.

A world is a YAML file::

    start: [x_m, y_m, heading_deg]      # base_link on the floor, heading CCW from +x
    goal: [x_m, y_m]
    goal_radius_m: 0.3
    obstacles:
      - {type: cylinder, x: 1.0, y: 0.2, radius_m: 0.1, height_m: 0.3}
      - {type: box, x: 2.0, y: -0.3, size_m: [0.2, 0.4, 0.3], yaw_deg: 30}
    floor_texture: carpet               # optional: one of WORLD_FLOOR_TEXTURES (sim/scene.py)

Optional keys ``name`` and ``description``. A bad world is refused whole with every problem listed
(WorldError), each naming the key and the value (a short, escaped piece of it), as mission files are.
Every number is finite and bounded: coordinates within +-MAX_COORDINATE_M, sizes, heights and the
goal radius in (0, MAX_SIZE_M], angles within +-MAX_ANGLE_DEG, at most MAX_OBSTACLES obstacles; a
world beyond them is refused here, before a scene is built from it.
"""
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, Optional, Sequence, Tuple

from ..safe_yaml import YamlFileError, load_yaml_file, short_repr

#: Floor appearances a world may ask for (the textures themselves: sim/scene.py); the generated
#: worlds and the classifier's training renders draw from FLOOR_TEXTURES.
FLOOR_TEXTURES = ("plain", "checker", "carpet", "tiles", "concrete")
#: Floors the visual odometry tracks on (nav runs' pose source vo needs one): random dots of a few cm.
#: On FLOOR_TEXTURES it loses track (too few features at its 320x240: the carpet's and concrete's dots
#: are sub-millimetre, the checker's and tiles' squares 25-33 cm).
ODOMETRY_FLOOR_TEXTURES = ("dots",)
WORLD_FLOOR_TEXTURES = FLOOR_TEXTURES + ODOMETRY_FLOOR_TEXTURES
WORLD_KEYS = ("name", "description", "start", "goal", "goal_radius_m", "obstacles", "floor_texture")
CYLINDER_KEYS = ("type", "x", "y", "radius_m", "height_m")
BOX_KEYS = ("type", "x", "y", "size_m", "yaw_deg")
MAX_COORDINATE_M = 100.0     # |x|, |y| of the start, the goal and every obstacle
MAX_SIZE_M = 10.0            # goal radius, a cylinder's radius and height, a box's edges
MAX_ANGLE_DEG = 360.0        # |start heading|, |box yaw|
MAX_OBSTACLES = 1000


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
                                      f"obstacles; got a {type(data).__name__}"])
        for key in data:
            if key not in WORLD_KEYS:
                problems.append(f"{key}: unknown key (value {short_repr(data[key])}); known: {', '.join(WORLD_KEYS)}")
        start = _numbers(data, "start", (MAX_COORDINATE_M, MAX_COORDINATE_M, MAX_ANGLE_DEG), problems)
        goal = _numbers(data, "goal", (MAX_COORDINATE_M, MAX_COORDINATE_M), problems)
        radius = _size(data, "goal_radius_m", "goal_radius_m", problems)
        raw_obstacles = data.get("obstacles", [])
        obstacles: List[Obstacle] = []
        if raw_obstacles is None:
            raw_obstacles = []
        if not isinstance(raw_obstacles, list):
            problems.append(f"obstacles: expected a list, got {short_repr(raw_obstacles)}")
            raw_obstacles = []
        elif len(raw_obstacles) > MAX_OBSTACLES:
            problems.append(f"obstacles: at most {MAX_OBSTACLES}, got {len(raw_obstacles)}")
            raw_obstacles = []
        for i, item in enumerate(raw_obstacles):
            ob = _obstacle(item, f"obstacles[{i}]", problems)
            if ob is not None:
                obstacles.append(ob)
        floor = data.get("floor_texture", "plain")
        if floor not in WORLD_FLOOR_TEXTURES:
            problems.append(f"floor_texture: unknown texture {short_repr(floor)}; "
                            f"known: {', '.join(WORLD_FLOOR_TEXTURES)}")
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


def _within(v, bound: float, unit: str, where: str, problems: List[str]) -> bool:
    """v a finite number within +-bound; else a problem naming where and the value."""
    if not _finite(v):
        problems.append(f"{where}: must be a finite number ({unit}), got {short_repr(v)}")
    elif abs(v) > bound:
        problems.append(f"{where}: must be within +-{bound:g} {unit}, got {v:g}")
    else:
        return True
    return False


def _numbers(data: dict, key: str, bounds: Sequence[float], problems: List[str]) -> Optional[List[float]]:
    """A list of len(bounds) numbers: metres within +-MAX_COORDINATE_M, the third (a heading) degrees."""
    v = data.get(key)
    if key not in data:
        problems.append(f"{key}: missing (a list of {len(bounds)} numbers)")
        return None
    if not isinstance(v, list) or len(v) != len(bounds):
        problems.append(f"{key}: expected a list of {len(bounds)} finite numbers, got {short_repr(v)}")
        return None
    ok = [_within(x, bound, "deg" if i == 2 else "m", f"{key}[{i}]", problems)
          for i, (x, bound) in enumerate(zip(v, bounds))]
    return [float(x) for x in v] if all(ok) else None


def _size(item: dict, key: str, where: str, problems: List[str]) -> float:
    """item[key]: a size in (0, MAX_SIZE_M] metres; 0.0 (with a problem naming where) otherwise."""
    v = item.get(key)
    if key not in item:
        problems.append(f"{where}: missing (a number in (0, {MAX_SIZE_M:g}] m)")
    elif not _finite(v) or not 0 < v <= MAX_SIZE_M:
        shown = f"{v:g}" if _finite(v) else short_repr(v)
        problems.append(f"{where}: must be a number in (0, {MAX_SIZE_M:g}] m, got {shown}")
    else:
        return float(v)
    return 0.0


def _obstacle(item: Any, where: str, problems: List[str]) -> Optional[Obstacle]:
    if not isinstance(item, dict):
        problems.append(f"{where}: expected a mapping with type cylinder or box, got {short_repr(item)}")
        return None
    kind = item.get("type")
    if kind not in ("cylinder", "box"):
        problems.append(f"{where}.type: must be cylinder or box, got {short_repr(kind)}")
        return None
    keys = CYLINDER_KEYS if kind == "cylinder" else BOX_KEYS
    before = len(problems)
    for key in item:
        if key not in keys:
            problems.append(f"{where}.{key}: unknown key for a {kind} (value {short_repr(item[key])}); "
                            f"known: {', '.join(keys)}")
    x_ok = _within(item.get("x"), MAX_COORDINATE_M, "m", f"{where}.x", problems)
    y_ok = _within(item.get("y"), MAX_COORDINATE_M, "m", f"{where}.y", problems)
    if kind == "cylinder":
        radius = _size(item, "radius_m", f"{where}.radius_m", problems)
        height = _size(item, "height_m", f"{where}.height_m", problems)
        if len(problems) > before or not (x_ok and y_ok):
            return None
        return Obstacle("cylinder", float(item["x"]), float(item["y"]), radius_m=radius, height_m=height)
    size = item.get("size_m")
    if not isinstance(size, list) or len(size) != 3:
        problems.append(f"{where}.size_m: expected [sx, sy, sz], three numbers in (0, {MAX_SIZE_M:g}] m, "
                        f"got {short_repr(size)}")
        size = None
    else:
        size = [_size({"s": s}, "s", f"{where}.size_m[{i}]", problems) for i, s in enumerate(size)]
    yaw = item.get("yaw_deg", 0.0)
    _within(yaw, MAX_ANGLE_DEG, "deg", f"{where}.yaw_deg", problems)
    if len(problems) > before or not (x_ok and y_ok):
        return None
    return Obstacle("box", float(item["x"]), float(item["y"]), size_m=tuple(size), yaw_deg=float(yaw))
