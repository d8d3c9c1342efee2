"""Mission files: loading and validation, ROS-free.

A mission is a YAML file. Minimal form::

    waypoints:
      - [x_m, y_m, heading_deg]     # world frame (the odometry frame), REP 103, heading CCW from +x

Optional keys: ``name``, ``description``, ``frame`` (world frame id, informational), ``time_limit_s``
(> 0; the mission stops when it runs out), ``tracker`` (overrides of config/tracker.yaml's
``tracker:`` keys, e.g. ``psi_wp_deg: 25``) and ``gaits`` (tracker gait -> gait library name, e.g.
``sidewind: sidewind_slow``) and ``disturbances`` (pushes and twists for the simulator, a list of
mappings checked by snake_autonomy.sim.disturbances; ignored on the robot).

A waypoint may also be a mapping ``{pose: [x_m, y_m, heading_deg], scout: {height_m: 0.3, hold_s: 5}}``:
a scout stop there once it is reached (missions/scout.py: keys, sequence). A waypoint
``{navigate_to: {x_m: 2.0, y_m: 0.5, radius_m: 0.2}}`` is a navigation leg: the obstacle-aware planner
drives there through its move_base action, not the tracker (missions/nav_leg.py: keys, outcomes).

A bad mission is refused whole, before anything moves, with every problem listed (MissionError);
each problem names the key and the value.
"""
import copy
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

from ..control.waypoint_tracker import TRACKER_GAITS, TrackerParams
from ..safe_yaml import MAX_FILE_BYTES, YamlFileError, load_yaml_file, load_yaml_text, short_repr
from ..paths import NotANameError, config_path, named_yaml
from .nav_leg import NavLegSpec, parse_nav_leg
from .scout import ScoutSpec, parse_scout

CONFIG_DIR = config_path()
MISSIONS_DIR = CONFIG_DIR / "missions"

#: Gait library names known without config/gaits.yaml (the driver's library).
DEFAULT_GAIT_LIBRARY = ("sidewind", "turn_left", "turn_right", "near_turn_left", "near_turn_right", "hold")

#: tracker: keys in files (units in the name) -> (TrackerParams field, factor to SI/radians)
TRACKER_KEYS = {
    "d_th_m": ("d_th", 1.0),
    "psi_wp_deg": ("psi_wp", math.pi / 180.0),
    "psi_turn_deg": ("psi_turn", math.pi / 180.0),
    "delta0_deg": ("delta0", math.pi / 180.0),
    "delta_lim_deg": ("delta_lim", math.pi / 180.0),
    "kp": ("kp", 1.0),
    "delta_turn_deg": ("delta_turn", math.pi / 180.0),
    "turn_exit_any_branch": ("turn_exit_any_branch", None),
    "far_blend_max_gap_deg": ("far_blend_max_gap", math.pi / 180.0),
}
#: Largest magnitude of a tracker key, in the file's units (metres, degrees, gain).
TRACKER_BOUNDS = {"d_th_m": 100.0, "kp": 1000.0}
MAX_TRACKER_DEG = 360.0
#: Run keys of config/tracker.yaml: (largest value, unit).
RUN_KEY_BOUNDS = {"rate_hz": (1000.0, "Hz"), "pose_timeout_s": (3600.0, "s"), "yaw_filter_window": (10000, "samples")}
#: Keys of a waypoint written as a mapping (missions/scout.py: the scout stop; missions/nav_leg.py: a
#: navigation leg, instead of pose).
WAYPOINT_KEYS = ("pose", "scout", "navigate_to")
MISSION_KEYS = ("name", "description", "frame", "waypoints", "time_limit_s", "tracker", "gaits", "disturbances")
# Physical ranges of a mission (a value outside is refused with its key and value).
MAX_WAYPOINTS = 1000
MAX_COORDINATE_M = 1000.0       # |x|, |y| of a waypoint
MAX_HEADING_DEG = 360.0         # |heading|
MAX_TIME_LIMIT_S = 86400.0      # one day
# A mission file or text: 1000 waypoints with scout stops take 75 KB. PyYAML parses about 100-170 KB
# a second here, while mission_node holds its lock: a 1 MiB mission_yaml kept mission/abort waiting 6-10 s.
MAX_MISSION_BYTES = 128 * 1024
# Position and heading closer than this count as the same waypoint.
DUPLICATE_TOL_M = 1e-3
DUPLICATE_TOL_DEG = 1e-2


class MissionError(ValueError):
    """A mission file that cannot run; ``problems`` lists every reason."""

    def __init__(self, source: str, problems: Sequence[str]):
        self.source = source
        self.problems = list(problems)
        super().__init__(f"{source}: {len(self.problems)} problem(s):\n  " + "\n  ".join(self.problems))


@dataclass
class Mission:
    name: str
    waypoints_deg: List[Tuple[float, float, float]]    # (x_m, y_m, heading_deg) as written
    tracker_params: Dict[str, Any]                     # TrackerParams fields, radians/metres
    gaits: Dict[str, str]                              # tracker gait -> gait library name
    scouts: Dict[int, ScoutSpec] = field(default_factory=dict)   # waypoint index -> scout stop there
    legs: Dict[int, NavLegSpec] = field(default_factory=dict)    # waypoint index -> navigate_to leg
    time_limit_s: Optional[float] = None
    description: str = ""
    frame: str = ""
    source: str = ""
    raw: Dict[str, Any] = field(default_factory=dict)  # the file's content, for the run log

    @property
    def waypoints(self) -> List[Tuple[float, float, float]]:
        """(x_m, y_m, heading_rad): what WaypointTracker takes."""
        return [(x, y, math.radians(h)) for x, y, h in self.waypoints_deg]

    def tracker_kwargs(self) -> Dict[str, Any]:
        return dict(self.tracker_params)

    def summary(self) -> str:
        p = self.tracker_params
        lines = [f"mission {_short(self.name)}: {len(self.waypoints_deg)} waypoint(s)"
                 + (f", time limit {self.time_limit_s:g} s" if self.time_limit_s else ", no time limit")]
        for i, (x, y, h) in enumerate(self.waypoints_deg):
            how = "navigate_to" if i in self.legs else "track"
            lines.append(f"  {i}: {how} x {x:+.3f} m  y {y:+.3f} m  heading {h:+.1f} deg"
                         + _leg_text(self.legs.get(i)) + _scout_text(self.scouts.get(i)))
        lines.append("  tracker: d_th {:.3f} m, psi_wp {:.1f} deg, psi_turn {:.1f} deg, delta0 {:.1f} deg, "
                     "delta_lim {:.1f} deg, kp {:g}".format(
                         p["d_th"], math.degrees(p["psi_wp"]), math.degrees(p["psi_turn"]),
                         math.degrees(p["delta0"]), math.degrees(p["delta_lim"]), p["kp"]))
        lines.append("  gaits: " + ", ".join(f"{k} -> {v}" for k, v in self.gaits.items()))
        return "\n".join(lines)


def _short(v) -> str:
    """A value as a problem message quotes it: a short, escaped piece (safe_yaml.short_repr)."""
    return short_repr(v)


def _scout_text(spec) -> str:
    if spec is None:
        return ""
    height = "highest head" if spec.height_m is None else f"head {spec.height_m:g} m"
    return f"  then scout: {height}, hold {spec.hold_s:g} s"


def _leg_text(spec) -> str:
    if spec is None:
        return ""
    return ((f", radius {spec.radius_m:g} m" if spec.radius_m is not None else "")
            + (f", time limit {spec.time_limit_s:g} s" if spec.time_limit_s is not None else ""))


def _waypoint_entry(wp: dict, i: int, scouts: Dict[int, "ScoutSpec"], legs: Dict[int, NavLegSpec],
                    problems: List[str]):
    """A waypoint written as a mapping {pose: [x_m, y_m, heading_deg], scout: {...}} or {navigate_to:
    {...}, scout: {...}}: its pose (None when missing or invalid), its scout stop recorded in `scouts`,
    its navigation leg in `legs`."""
    for key in wp:
        if key not in WAYPOINT_KEYS:
            problems.append(f"waypoints[{i}].{key}: unknown key (value {_short(wp[key])}); "
                            f"known: {', '.join(WAYPOINT_KEYS)}")
    if "scout" in wp:
        spec = parse_scout(wp["scout"], f"waypoints[{i}].scout", problems)
        if spec is not None:
            scouts[i] = spec
    if "navigate_to" in wp:
        if "pose" in wp:
            problems.append(f"waypoints[{i}].pose: give pose or navigate_to, not both (pose {_short(wp['pose'])})")
        spec = parse_nav_leg(wp["navigate_to"], f"waypoints[{i}].navigate_to", problems)
        if spec is None:
            return None
        legs[i] = spec
        return [spec.x_m, spec.y_m, spec.heading_deg]
    if "pose" not in wp:
        problems.append(f"waypoints[{i}].pose: missing ([x_m, y_m, heading_deg], or navigate_to: {{x_m, y_m}})")
        return None
    return wp["pose"]


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def load_yaml(path, max_bytes: int = MAX_FILE_BYTES) -> Any:
    """A YAML file through the package's bounded loader (safe_yaml); MissionError naming the file."""
    try:
        return load_yaml_file(path, max_bytes)
    except YamlFileError as exc:
        raise MissionError(str(path), [str(exc).removeprefix(f"{path}: ")]) from None


def gait_library_names(path=None) -> Tuple[str, ...]:
    """Gait names of the gait library (config/gaits.yaml), or the default set when it is absent.

    Accepts ``gaits: {name: {...}}``, ``gaits: [{name: ...}]`` or top-level ``name: {...}``.
    """
    path = Path(path) if path else CONFIG_DIR / "gaits.yaml"
    if not path.is_file():
        return DEFAULT_GAIT_LIBRARY
    data = load_yaml(path)
    if isinstance(data, dict) and "gaits" in data:
        data = data["gaits"]
    if isinstance(data, dict):
        names = [str(k) for k, v in data.items() if isinstance(v, dict)]
    elif isinstance(data, list):
        names = [str(g["name"]) for g in data if isinstance(g, dict) and "name" in g]
    else:
        names = []
    return tuple(names) or DEFAULT_GAIT_LIBRARY


#: Keys of config/tracker.yaml besides `tracker:` and `gaits:` (how the tracker is run).
RUN_KEYS = ("rate_hz", "pose_timeout_s", "yaw_filter_window", "heading_offset_deg")


def load_defaults(path=None, overrides: Optional[Dict[str, Any]] = None,
                  overrides_source: str = "overrides") -> Dict[str, Any]:
    """config/tracker.yaml (tracker parameters, rates, gait mapping, heading offset).

    ``overrides``: a flat mapping merged over the file, e.g. the ``tracker:`` section of
    config/sim.yaml (:func:`read_overrides`): tracker parameter keys (``delta0_deg``, ...), run keys
    (``rate_hz``, ``heading_offset_deg``, ...) and ``gaits`` (tracker gait -> library gait)."""
    path = Path(path) if path else CONFIG_DIR / "tracker.yaml"
    data = load_yaml(path)
    if not isinstance(data, dict):
        raise MissionError(str(path), [f"expected a mapping, got {_short(data)}"])
    data = dict(data)
    data.setdefault("heading_offset_deg", 0.0)
    source = str(path)
    if overrides:
        problems = []
        if not isinstance(overrides, dict):
            raise MissionError(overrides_source, [f"expected a mapping of tracker keys, got {_short(overrides)}"])
        section = dict(data.get("tracker") or {})
        for key, value in overrides.items():
            if key in TRACKER_KEYS:
                section[key] = value
            elif key in RUN_KEYS:
                data[key] = value
            elif key == "gaits" and isinstance(value, dict):
                data["gaits"] = {**(data.get("gaits") or {}), **value}
            else:
                problems.append(f"{key}: unknown key (value {_short(value)}); known: "
                                f"{', '.join(list(TRACKER_KEYS) + list(RUN_KEYS) + ['gaits'])}")
        if problems:
            raise MissionError(overrides_source, problems)
        data["tracker"] = section
        source = f"{path} + {overrides_source}"
    problems = []
    tracker, problems_t = _tracker_params(data.get("tracker", {}) or {}, TrackerParams().__dict__, "tracker")
    problems += problems_t
    for key, kind in (("rate_hz", float), ("pose_timeout_s", float), ("yaw_filter_window", int)):
        v = data.get(key)
        if not _is_number(v) or not math.isfinite(v) or v <= 0 or (kind is int and int(v) != v):
            problems.append(f"{key}: must be a positive {'integer' if kind is int else 'number'}, got {_short(v)}")
        elif v > RUN_KEY_BOUNDS[key][0]:
            problems.append(f"{key}: must be at most {RUN_KEY_BOUNDS[key][0]:g} {RUN_KEY_BOUNDS[key][1]}, "
                            f"got {_short(v)}")
    v = data.get("heading_offset_deg")
    if not _is_number(v) or not math.isfinite(v) or abs(v) > 180.0:
        problems.append(f"heading_offset_deg: must be a number in [-180, 180], got {_short(v)}")
    gaits = data.get("gaits") or {}
    if not isinstance(gaits, dict):
        problems.append(f"gaits: expected a mapping of tracker gait -> library gait, got {_short(gaits)}")
        gaits = {}
    if problems:
        raise MissionError(source, problems)
    out = dict(data)
    out["tracker"] = tracker
    out["gaits"] = {g: str(gaits.get(g, "hold" if g == "stop" else g)) for g in TRACKER_GAITS}
    out["source"] = source
    return out


def read_overrides(path, section: str = "tracker") -> Dict[str, Any]:
    """The ``section`` mapping of a YAML file (e.g. config/sim.yaml's ``tracker:``), {} when absent."""
    data = load_yaml(path) or {}
    if not isinstance(data, dict):
        raise MissionError(str(path), [f"expected a mapping, got {_short(data)}"])
    value = data.get(section) or {}
    if not isinstance(value, dict):
        raise MissionError(str(path), [f"{section}: expected a mapping of tracker keys, got {_short(value)}"])
    return dict(value)


def _tracker_params(section, base: Dict[str, Any], where: str):
    params = dict(base)
    problems = []
    unknown = []
    if not isinstance(section, dict):
        return params, [f"{where}: expected a mapping, got {_short(section)}"]
    for key, value in section.items():
        if key not in TRACKER_KEYS:
            unknown.append(f"{where}.{key}: unknown key (value {_short(value)}); known: {', '.join(TRACKER_KEYS)}")
            continue
        name, factor = TRACKER_KEYS[key]
        if factor is None:
            if not isinstance(value, bool):
                problems.append(f"{where}.{key}: must be true or false, got {_short(value)}")
                continue
            params[name] = value
        elif not _is_number(value) or not math.isfinite(value):
            problems.append(f"{where}.{key}: must be a finite number, got {_short(value)}")
        elif abs(value) > TRACKER_BOUNDS.get(key, MAX_TRACKER_DEG):
            problems.append(f"{where}.{key}: must be within +-{TRACKER_BOUNDS.get(key, MAX_TRACKER_DEG):g}, "
                            f"got {_short(value)}")
        else:
            params[name] = float(value) * factor
    if not problems:
        for p in TrackerParams(**params).problems():
            # name the file's key (with its unit) rather than the internal field
            field_name = p.split(":", 1)[0]
            key = next((k for k, (n, _) in TRACKER_KEYS.items() if n == field_name), field_name)
            factor = TRACKER_KEYS.get(key, (None, None))[1]
            value = params.get(field_name)
            shown = value / factor if factor not in (None, 1.0) and _is_number(value) else value
            problems.append(f"{where}.{key}: {p.split(':', 1)[1].strip()} (value {shown:.6g})"
                            if _is_number(shown) else f"{where}.{key}: {p.split(':', 1)[1].strip()}")
    return params, unknown + problems


def validate_mission(data: Any, source: str = "<mission>", defaults: Optional[Dict[str, Any]] = None,
                     gait_library: Optional[Sequence[str]] = None) -> Mission:
    """Checks a parsed mission; returns a Mission or raises MissionError listing every problem."""
    defaults = defaults if defaults is not None else load_defaults()
    library = tuple(gait_library) if gait_library is not None else gait_library_names()
    problems: List[str] = []
    if not isinstance(data, dict):   # the type only: a file that is no mission is not quoted
        raise MissionError(source, [f"expected a mapping with a 'waypoints' list, got {_type_name(data)}"])

    for key in data:
        if key not in MISSION_KEYS:
            problems.append(f"{key}: unknown key (value {_short(data[key])}); known: {', '.join(MISSION_KEYS)}")

    waypoints: List[Tuple[float, float, float]] = []
    scouts: Dict[int, ScoutSpec] = {}
    legs: Dict[int, NavLegSpec] = {}
    raw_wps = data.get("waypoints")
    if "waypoints" not in data:
        problems.append("waypoints: missing (a list of [x_m, y_m, heading_deg])")
    elif not isinstance(raw_wps, list):
        problems.append(f"waypoints: expected a list of [x_m, y_m, heading_deg], got {_short(raw_wps)}")
    elif not raw_wps:
        problems.append("waypoints: the list is empty; at least one waypoint is needed")
    elif len(raw_wps) > MAX_WAYPOINTS:
        problems.append(f"waypoints: at most {MAX_WAYPOINTS} waypoints, got {len(raw_wps)}")
    else:
        for i, wp in enumerate(raw_wps):
            if isinstance(wp, dict):
                wp = _waypoint_entry(wp, i, scouts, legs, problems)
                if wp is None:
                    waypoints.append(None)
                    continue
            if not isinstance(wp, (list, tuple)) or len(wp) != 3:
                problems.append(f"waypoints[{i}]: expected [x_m, y_m, heading_deg], got {_short(wp)}")
                waypoints.append(None)
                continue
            ok = True
            for j, (label, v) in enumerate(zip(("x_m", "y_m", "heading_deg"), wp)):
                if not _is_number(v):
                    problems.append(f"waypoints[{i}][{j}] ({label}): expected a number, got {_short(v)}")
                    ok = False
                elif not math.isfinite(v):
                    problems.append(f"waypoints[{i}][{j}] ({label}): must be finite, got {_short(v)}")
                    ok = False
                elif abs(v) > (MAX_HEADING_DEG if j == 2 else MAX_COORDINATE_M):
                    bound = MAX_HEADING_DEG if j == 2 else MAX_COORDINATE_M
                    problems.append(f"waypoints[{i}][{j}] ({label}): must be within +-{bound:g}, got {_short(v)}")
                    ok = False
            waypoints.append(tuple(float(v) for v in wp) if ok else None)
        for i in range(1, len(waypoints)):
            a, b = waypoints[i - 1], waypoints[i]
            if a is None or b is None:
                continue
            dh = abs((b[2] - a[2] + 180.0) % 360.0 - 180.0)
            if math.hypot(b[0] - a[0], b[1] - a[1]) < DUPLICATE_TOL_M and dh < DUPLICATE_TOL_DEG:
                problems.append(f"waypoints[{i}]: duplicate of waypoints[{i - 1}] {list(a)} "
                                f"(consecutive waypoints must differ in position or heading)")

    name = data.get("name", Path(source).stem if source else "mission")
    if not isinstance(name, str) or not name.strip():
        problems.append(f"name: expected a non-empty string, got {_short(name)}")
    for key in ("description", "frame"):
        if key in data and not isinstance(data[key], str):
            problems.append(f"{key}: expected a string, got {_short(data[key])}")

    dist = data.get("disturbances")
    if dist is not None and (not isinstance(dist, list) or not all(isinstance(d, dict) for d in dist)):
        problems.append(f"disturbances: expected a list of mappings (simulator pushes and twists), got {_short(dist)}")

    time_limit = data.get("time_limit_s")
    if time_limit is not None and (not _is_number(time_limit) or not math.isfinite(time_limit) or time_limit <= 0
                                   or time_limit > MAX_TIME_LIMIT_S):
        problems.append(f"time_limit_s: must be a positive number of seconds up to {MAX_TIME_LIMIT_S:g}, "
                        f"got {_short(time_limit)}")

    tracker, tracker_problems = _tracker_params(data.get("tracker") or {}, defaults["tracker"], "tracker")
    problems += tracker_problems

    gaits = dict(defaults["gaits"])
    raw_gaits = data.get("gaits") or {}
    if not isinstance(raw_gaits, dict):
        problems.append(f"gaits: expected a mapping of tracker gait -> library gait, got {_short(raw_gaits)}")
        raw_gaits = {}
    for role, gait in raw_gaits.items():
        if role not in TRACKER_GAITS:
            problems.append(f"gaits.{role}: unknown tracker gait (value {_short(gait)}); "
                            f"known: {', '.join(TRACKER_GAITS)}")
        else:
            gaits[role] = gait
    for role, gait in gaits.items():
        if not isinstance(gait, str) or gait not in library:
            where = f"gaits.{role}" if role in raw_gaits else f"gaits.{role} (default)"
            problems.append(f"{where}: unknown gait {_short(gait)}; the gait library has: {', '.join(library)}")

    if problems:
        raise MissionError(source, problems)
    return Mission(name=name, waypoints_deg=list(waypoints), tracker_params=tracker, gaits=gaits,
                   scouts=scouts, legs=legs, time_limit_s=float(time_limit) if time_limit is not None else None,
                   description=data.get("description", ""), frame=data.get("frame", ""),
                   source=source, raw=copy.deepcopy(data))


def _type_name(value) -> str:
    return "nothing (an empty document)" if value is None else f"a {type(value).__name__}"


def _path_text(path) -> str:
    """A path as a message shows it: as is when short and printable, else quoted (short_repr)."""
    text = str(path)
    return text if text.isprintable() and len(text) <= 200 else short_repr(text)


def resolve_mission_path(name_or_path: str) -> Path:
    """A mission file (a path ending in .yaml or .yml) or a provided mission's name, which resolves
    only to config/missions/NAME.yaml (paths.named_yaml); anything else is refused (MissionError)
    before a byte is read: a name like ../../etc/passwd never reaches a file outside the folder."""
    try:
        return named_yaml("missions", name_or_path)
    except NotANameError as exc:
        raise MissionError(exc.value, [exc.problem]) from None


def load_mission(path, defaults=None, gait_library=None) -> Mission:
    """Reads and validates a mission file (a path ending in .yaml/.yml, or a provided mission's name)."""
    p = resolve_mission_path(str(path))
    source = _path_text(p)
    try:
        data = load_yaml(p, MAX_MISSION_BYTES)
    except FileNotFoundError:
        raise MissionError(source, [f"file not found: {source}"]) from None
    return validate_mission(data, source, defaults, gait_library)


def mission_from_text(text: str, source: str, defaults=None, gait_library=None) -> Mission:
    """A mission held in memory as YAML text (a RunMission goal's mission_yaml), read by the same
    bounded loader as the files (safe_yaml.load_yaml_text: size cap, no aliases, no duplicate keys)."""
    try:
        data = load_yaml_text(text, source, MAX_MISSION_BYTES)
    except YamlFileError as exc:
        raise MissionError(source, [str(exc).removeprefix(f"{source}: ")]) from None
    return validate_mission(data, source, defaults, gait_library)
