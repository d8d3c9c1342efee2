"""config/nav.yaml: camera, traversability, sampler and follower parameters, every problem listed.

NavConfig() is config/nav.yaml's values: a file that omits a key plans as nav.yaml does. One schema,
checked where a file is loaded (NavConfig.from_dict): unknown sections and keys are refused, each
key's type is its default's (true/false, a string, an integer, a number; never nan), and each
section's validate() checks the ranges; every problem is named with its section.key and value, all
at once.

A robot's own values live in config/nav_<robot>.yaml (e.g. nav_chang_rectilinear.yaml): a file with
`base: nav.yaml` and only the keys that differ, merged key by key over its base. nav_config_path(robot)
is the one place that picks the file a robot's runs use when none is named."""
import math
import dataclasses
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Dict, List

import numpy as np

from ...paths import config_path
from ...safe_yaml import load_yaml_file
from ...perception.depth_traversability import DepthTraversabilityParams
from ...perception.camera_model import CameraIntrinsics, CameraMount
from .follower import FollowerParams
from .gait import RectilinearGait
from .body_sweep import SweepParams
from .critics import CriticParams
from .local_map import LocalMapParams
from .obstacle_map import MapParams
from .recovery import RecoveryParams
from .sampler import SamplerParams

NAV_YAML = config_path("nav.yaml")
# the keys whose number may be .inf (the option off); every other number must be finite
MAY_BE_INFINITE = {"sampler": ("obstacle_depth_m", "known_free_m", "blocked_wins_depth_m"),
                   "depth_traversability": ("max_range_m",)}
CAMERA_KEYS = {"camera": ("intrinsics", "mount"), "camera.mount": ("translation_m", "rpy_deg"),
               "camera.intrinsics": ("width", "height", "fx", "fy", "cx", "cy")}


class NavConfigError(ValueError):
    def __init__(self, source: str, problems: List[str]):
        self.problems = list(problems)
        super().__init__(f"{source}: {len(problems)} problem(s):\n  " + "\n  ".join(problems))


@dataclass
class ClassifierParams:
    block_px: int = 40
    dct_coefficients: int = 4
    svm_c: float = 10.0
    stride_px: int = 20       # each 20 px cell judged by the 40 px block centred on it
    ground_margin: float = 0.0   # a block is ground when the SVM's decision value exceeds this
                                 # (0: the SVM's own class; > 0: fewer obstacles taken for floor, more
                                 # floor for obstacles); applied when classifying, not stored in the model
    ground_fraction: float = 0.5  # a block's training label (and perception truth's cell) is
                                  # ground when at least this fraction of it is; stored in the model

    def validate(self) -> List[str]:
        p = [f"{key}: must be > 0, got {getattr(self, key)}"
             for key in ("block_px", "dct_coefficients", "svm_c") if not 0 < getattr(self, key) < math.inf]
        if not math.isfinite(self.ground_margin):
            p.append(f"ground_margin: must be finite, got {self.ground_margin}")
        if not 0 < self.ground_fraction <= 1:
            p.append(f"ground_fraction: must be in (0, 1], got {self.ground_fraction}")
        if not 0 < self.stride_px <= self.block_px:
            p.append(f"stride_px: must be in (0, block_px = {self.block_px}], got {self.stride_px}")
        return p


@dataclass(frozen=True)
class PlantOptions:
    """Simulator options of the navigation runs (nav.yaml `plant:`), over config/sim.yaml's."""
    flat_belly_fraction: float = 0.8   # physics.flat_belly_fraction for nav runs (sim/mjcf.py)

    def validate(self) -> List[str]:
        if not 0.0 <= self.flat_belly_fraction <= 1.0:
            return [f"flat_belly_fraction: must be in [0, 1], got {self.flat_belly_fraction}"]
        return []


STEERING_LAWS = ("uniform", "follow_the_leader")


@dataclass(frozen=True)
class NavGaits:
    """config/gaits.yaml entries a navigation run drives through the driver (nav.yaml `gaits:`), each
    with steering: curvature (curve + kappa)."""
    forward: str = "rectilinear"             # head first
    reverse: str = "rectilinear_reverse"     # tail first (backing off)
    stop: str = "hold_curve"                 # the wave decays, the yaw joints keep kappa: the body stays
                                             # as it is (the straight `hold` swings the head (L^2/8) kappa
                                             # sideways: 0.28 m per 1/m on COBRA, out of a goal's disc)
    steering: str = "uniform"                # uniform: every yaw joint at kappa (the driver's curvature
                                             # law, what the navigation loop commands); follow_the_leader:
                                             # kappa laid along the head's path (follow_the_leader.py, a
                                             # prototype measured by bench/nav_follow_the_leader only)

    def command(self, hold: bool, backwards: bool) -> str:
        """The gait of a loop command (NavTick hold / backwards): stop, reverse or forward."""
        return self.stop if hold else self.reverse if backwards else self.forward

    @classmethod
    def from_dict(cls, d, problems: List[str]) -> "NavGaits":
        d = d or {}
        if not isinstance(d, dict):
            problems.append(f"gaits: expected a mapping, got {d!r}")
            return cls()
        kwargs = {}
        for key, value in d.items():
            if key not in ("forward", "reverse", "stop", "steering"):
                problems.append(f"gaits.{key}: unknown key (value {value!r}); known: forward, reverse, stop, "
                                "steering")
            elif key == "steering" and value not in STEERING_LAWS:
                problems.append(f"gaits.steering: expected one of {', '.join(STEERING_LAWS)}, got {value!r}")
            elif not isinstance(value, str) or not value:
                problems.append(f"gaits.{key}: expected a gait name of config/gaits.yaml, got {value!r}")
            else:
                kwargs[key] = value
        return cls(**kwargs)




PLANNERS = ("perception_space", "layered")


@dataclass(frozen=True)
class PlannerChoice:
    """config/nav.yaml `planner:`: which local planner the loop runs."""
    kind: str = "layered"               # layered (layered_planner.py) | perception_space (planner.py)

    def validate(self) -> List[str]:
        return [] if self.kind in PLANNERS else [f"kind: expected one of {', '.join(PLANNERS)}, got {self.kind!r}"]


@dataclass
class NavConfig:
    """config/nav.yaml; the defaults are its values (COBRA's)."""
    intrinsics: CameraIntrinsics = field(default_factory=CameraIntrinsics.d435i_like)
    mount: CameraMount = CameraMount()
    depth: DepthTraversabilityParams = field(default_factory=DepthTraversabilityParams)
    sampler: SamplerParams = field(default_factory=SamplerParams)
    follower: FollowerParams = field(default_factory=FollowerParams)
    classifier: ClassifierParams = field(default_factory=ClassifierParams)
    replan_period_s: float = 10.0
    gait: RectilinearGait = RectilinearGait()
    plant: PlantOptions = PlantOptions()
    gaits: NavGaits = NavGaits()
    map: MapParams = MapParams()
    planner: PlannerChoice = PlannerChoice()
    local_map: LocalMapParams = LocalMapParams()
    body_sweep: SweepParams = SweepParams()
    critics: CriticParams = CriticParams()
    recovery: RecoveryParams = RecoveryParams()

    @classmethod
    def from_yaml(cls, path=None) -> "NavConfig":
        path = Path(path) if path else NAV_YAML
        return cls.from_dict(_load_with_base(path), str(path))

    @classmethod
    def from_dict(cls, data: Dict[str, Any], source: str = "nav.yaml") -> "NavConfig":
        problems: List[str] = []
        if not isinstance(data, dict):
            raise NavConfigError(source, [f"expected a mapping of sections, got {data!r}"])
        known = ("camera", "depth_traversability", "sampler", "follower", "classifier", "gait", "plant", "gaits",
                 "map", "planner", "local_map", "body_sweep", "critics", "recovery")
        for key in data:
            if key not in known:
                problems.append(f"{key}: unknown section; known: {', '.join(known)}")
        defaults = cls()
        cam = _mapping(data.get("camera"), "camera", problems)
        intr = defaults.intrinsics
        intr_d = _mapping(cam.get("intrinsics"), "camera.intrinsics", problems)
        if intr_d:
            try:
                intr = CameraIntrinsics.from_dict(intr_d)
            except ValueError as e:
                problems.extend(str(e).split("; "))
            problems += [f"camera.intrinsics.{k}: must be an integer, got {intr_d[k]!r}" for k in ("width", "height")
                         if _number(intr_d.get(k)) and math.isfinite(intr_d[k]) and intr_d[k] != int(intr_d[k])]
        mount_d = _mapping(cam.get("mount"), "camera.mount", problems)
        mount = defaults.mount
        t, rpy = mount_d.get("translation_m", mount.translation_m), mount_d.get("rpy_deg", mount.rpy_deg)
        if not _vec3(t):
            problems.append(f"camera.mount.translation_m: expected 3 numbers, got {t!r}")
        if not _vec3(rpy):
            problems.append(f"camera.mount.rpy_deg: expected 3 numbers, got {rpy!r}")
        if _vec3(t) and _vec3(rpy):
            mount = CameraMount(tuple(float(x) for x in t), tuple(float(x) for x in rpy))
        follower_d = _with_gait_map(data.get("follower"), source, problems)
        replan = follower_d.pop("replan_period_s", defaults.replan_period_s)
        if not _number(replan) or not 0 < replan < math.inf:
            problems.append(f"follower.replan_period_s: must be a number > 0, got {replan!r}")
        depth = _section(defaults.depth, data.get("depth_traversability"), "depth_traversability", problems)
        sampler = _section(defaults.sampler, data.get("sampler"), "sampler", problems)
        follower = _section(defaults.follower, follower_d, "follower", problems)
        classifier = _section(defaults.classifier, data.get("classifier"), "classifier", problems)
        gait = _section(defaults.gait, data.get("gait"), "gait", problems)
        plant = _section(defaults.plant, data.get("plant"), "plant", problems)
        gaits = NavGaits.from_dict(data.get("gaits"), problems)
        omap = _section(defaults.map, data.get("map"), "map", problems)
        layers = {name: _section(getattr(defaults, name), data.get(name), name, problems)
                  for name in ("planner", "local_map", "body_sweep", "critics", "recovery")}
        for key in ("amplitude_m", "wavelength_m", "frequency_hz"):
            if not getattr(gait, key) > 0:
                problems.append(f"gait.{key}: must be > 0, got {getattr(gait, key)}")
        for name, obj in (("depth_traversability", depth), ("sampler", sampler), ("follower", follower),
                          ("plant", plant), ("classifier", classifier), ("map", omap), *layers.items()):
            problems += [f"{name}.{p}" for p in obj.validate()]
        if problems:
            raise NavConfigError(source, problems)
        return cls(intr, mount, depth, sampler, follower, classifier, float(replan), gait, plant, gaits, omap,
                   **layers)


def nav_config_path(robot: str) -> Path:
    """The nav config of a robot's runs when none is named: config/nav_<NAME>.yaml if it exists (a
    robot given as a YAML file: its stem), else config/nav.yaml (COBRA's values)."""
    own = config_path(f"nav_{Path(robot).stem}.yaml")
    return own if own.exists() else NAV_YAML


def _load_with_base(path: Path, depth: int = 0) -> Dict[str, Any]:
    """The file's mapping; with `base: FILE` (relative: to the file's folder) the base's mapping with
    this file's sections merged over it key by key (a section's keys replace the base's)."""
    data = load_yaml_file(path) or {}
    if not isinstance(data, dict):
        return data
    data = dict(data)
    if isinstance(data.get("follower"), dict) and "gait_map" in data["follower"]:
        # this file's gait map under this file's own follower keys, before a base is merged under
        # them: a base's keys never override the map the file names
        problems: List[str] = []
        data["follower"] = _with_gait_map(data["follower"], str(path), problems)
        if problems:
            raise NavConfigError(str(path), problems)
    if "base" not in data:
        return data
    base_name = data.pop("base")
    if not isinstance(base_name, str) or not base_name:
        raise NavConfigError(str(path), [f"base: expected a nav config file name, got {base_name!r}"])
    base_path = Path(path).parent / base_name
    if not base_path.exists() or depth > 4:
        raise NavConfigError(str(path), [f"base: no such file {base_name!r} (beside {path})" if depth <= 4
                                         else f"base: {base_name!r}: bases nested deeper than 5"])
    merged = dict(_load_with_base(base_path, depth + 1))
    for key, value in data.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged


def _with_gait_map(follower, source: str, problems: List[str]):
    """A follower section with its `gait_map: FILE` expanded: the map's follower keys, and over them
    the keys the section names itself (e.g. a map's fit with a wider kappa_max_per_m)."""
    follower = follower or {}
    if not isinstance(follower, dict):
        problems.append(f"follower: expected a mapping, got {follower!r}")
        return {}
    if "gait_map" not in follower:
        return dict(follower)
    own = dict(follower)
    merged = _gait_map_follower(own.pop("gait_map"), source, problems)
    merged.update(own)
    return merged


def _gait_map_follower(name, source: str, problems: List[str]) -> Dict[str, Any]:
    """follower.gait_map: a file of `snake_autonomy gait-map` (relative: to the nav config's folder,
    then the package's config/); its `follower:` keys, under the keys the section names itself."""
    if not isinstance(name, str) or not name:
        problems.append(f"follower.gait_map: expected a file name, got {name!r}")
        return {}
    path = Path(name)
    if not path.is_absolute():
        here = Path(source).parent / path
        path = here if here.exists() else config_path(name)
    if not path.exists():
        problems.append(f"follower.gait_map: no such file {name!r} (run snake_autonomy gait-map --out DIR)")
        return {}
    follower = (load_yaml_file(path) or {}).get("follower")
    if not isinstance(follower, dict):
        problems.append(f"follower.gait_map: {name!r} has no follower: section")
        return {}
    return follower


def _vec3(v) -> bool:
    return isinstance(v, (list, tuple)) and len(v) == 3 and all(
        isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in v)


def _mapping(d, name: str, problems: List[str]) -> Dict[str, Any]:
    """A camera (sub)section: a mapping of known keys (CAMERA_KEYS); else named, and {}."""
    if d is None:
        return {}
    if not isinstance(d, dict):
        problems.append(f"{name}: expected a mapping, got {d!r}")
        return {}
    problems += [f"{name}.{k}: unknown key (value {v!r}); known: {', '.join(CAMERA_KEYS[name])}"
                 for k, v in d.items() if k not in CAMERA_KEYS[name]]
    return d


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and not math.isnan(value)


def _section(default, d, name: str, problems: List[str]):
    """A section's mapping over its default dataclass: each key's type is the default's (true or
    false; a string; an integer; a number, never nan), a key of the wrong type keeps its default
    (and is named); ranges are the dataclass's validate()."""
    d = d or {}
    if not isinstance(d, dict):
        problems.append(f"{name}: expected a mapping, got {d!r}")
        return default
    known = [f.name for f in fields(default)]
    kwargs = {}
    for key, value in d.items():
        if key not in known:
            problems.append(f"{name}.{key}: unknown key (value {value!r}); known: {', '.join(known)}")
            continue
        was = getattr(default, key)
        if isinstance(was, tuple):
            ok, want = isinstance(value, list) and all(isinstance(v, str) for v in value), "a list of names"
            if ok:
                kwargs[key] = tuple(value)
                continue
        elif isinstance(was, bool):
            ok, want = isinstance(value, bool), "true or false"
        elif isinstance(was, str):
            ok, want = isinstance(value, str), "a string"
        elif isinstance(was, int):
            ok, want = _number(value) and math.isfinite(value) and value == int(value), "an integer"
        elif key in MAY_BE_INFINITE.get(name, ()):
            ok, want = _number(value), "a number (.inf: off)"
        else:
            ok, want = _number(value) and math.isfinite(value), "a finite number"
        if ok:
            kwargs[key] = value if isinstance(was, (bool, str)) else type(was)(value)
        else:
            problems.append(f"{name}.{key}: must be {want}, got {value!r}")
    return dataclasses.replace(default, **kwargs)


def head_width_m(robot_yaml) -> float:
    """The head's footprint width: `head_width_m` of the robot YAML, else the capsule's diameter."""
    data = load_yaml_file(robot_yaml) or {}
    if "head_width_m" in data:
        w = data["head_width_m"]
        if not isinstance(w, (int, float)) or isinstance(w, bool) or not w > 0:
            raise NavConfigError(str(robot_yaml), [f"head_width_m: must be a number > 0, got {w!r}"])
        return float(w)
    return 2.0 * float(data["link_radius_m"])


def T_ground_camera(mount: CameraMount, base_height_m: float) -> np.ndarray:
    """The optical frame in the ground frame (under base_link, level): base_link base_height_m up."""
    t = np.eye(4)
    t[2, 3] = base_height_m
    return t @ mount.T_base_optical()
