"""Configuration of the simulated robot (config/sim.yaml) and its per-seed randomisation.

Every numeric key accepts either one number (fixed) or a two-element list ``[lo, hi]``: a range
from which `SimConfig.draw(seed)` takes one value per seed (uniformly; per joint for servo gains).
`draw(seed, randomize=False)` takes the midpoint of every range instead, keeping the seed only for
the sensors' noise sequences. Every random number of a simulation comes from a stream derived from
the seed and a fixed stream name (`SimParams.rng`), so adding a consumer never shifts another's.

`SimConfig.from_yaml` collects every problem (key, value, reason) before raising one ValueError.
The keys, their units and defaults are the dataclass fields below; config/sim.yaml documents them.
"""
import dataclasses
import math
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional

import numpy as np

from ..missions.mission import MissionError, load_defaults
from ..paths import config_path
from ..safe_yaml import load_yaml_file
from .depth_noise import DepthNoiseConfig
from .imu import ImuConfig


@dataclass(frozen=True)
class Range:
    """A closed interval [lo, hi]; lo == hi is a fixed value."""
    lo: float
    hi: float

    @property
    def nominal(self) -> float:
        return 0.5 * (self.lo + self.hi)

    def draw(self, rng: np.random.Generator, size=None):
        if self.lo == self.hi:
            return self.lo if size is None else np.full(size, self.lo)
        return rng.uniform(self.lo, self.hi, size)


@dataclass
class PhysicsConfig:
    timestep_s: float = 0.002           # MuJoCo step; 0.001-0.002 are stable
    integrator: str = "implicitfast"    # MuJoCo integrator: implicitfast | implicit | RK4 | Euler
    cone: str = "pyramidal"             # friction cone: pyramidal (30 % faster) | elliptic
    floor_friction: Range = Range(0.6, 0.8)  # Coulomb sliding coefficient, link capsule on floor
    torsional_friction: float = 0.0     # > 0 switches contacts to condim 4 (slower)
    rolling_friction_m: float = 0.01    # > 0: condim 6, rolling torque = this x normal force
    contact_timeconst_s: float = 0.01   # MuJoCo solref[0]: contact stiffness (>= 2 timesteps)
    contact_dampratio: float = 1.0      # MuJoCo solref[1]
    solver_iterations: int = 30
    self_collision: bool = False        # contacts between non-adjacent links
    start_height_m: float = 0.001       # clearance of the capsules above the floor at t = 0
    flat_belly_fraction: float = 0.0    # > 0: a flat box under each link, this fraction of the
                                        # capsule's diameter wide (sim/mjcf.py); 0: round links


@dataclass
class ServoConfig:
    torque_limit_nm: float = 9.9            # XH540-W270 stall torque (thesis 3.1)
    speed_limit_rad_s: float = 4.8          # XH540-W270 no-load speed, 46 rpm at 12 V
    kp_nm_per_rad: Range = Range(80.0, 120.0)    # position gain, drawn per joint
    kv_nm_s_per_rad: Range = Range(1.5, 2.5)    # velocity gain, drawn per joint
    armature_kg_m2: float = 0.01            # reflected rotor inertia (gear ratio 272.5)
    damping_nm_s_per_rad: float = 0.2       # gear train viscous friction (also when limp)
    frictionloss_nm: float = 0.05           # gear train dry friction (also when limp)
    torque_constant_nm_per_a: float = 2.25  # Present Current = torque / this (9.9 N m / 4.4 A)
    setpoint_period_s: float = 0.01         # a new goal is reached over this (speed permitting)


@dataclass
class MocapConfig:
    rate_hz: float = 100.0
    position_noise_m: Range = Range(0.0005, 0.0005)     # white, per axis (std)
    rotation_noise_rad: Range = Range(0.002, 0.002)     # white, per axis (std)


@dataclass
class VioConfig:
    rate_hz: float = 30.0
    latency_s: float = 0.05             # sample to the planner (nav runs): odometry + transport
    calibration: str = "camera.yaml"    # T_head^camera, relative to the sim.yaml that names it
    position_noise_m: Range = Range(0.005, 0.015)       # white, per axis (std)
    rotation_noise_rad: Range = Range(0.005, 0.015)     # white, per axis (std)
    # random walk of the odometry frame: config/sim.yaml's fit to the thesis's RTAB-Map (it says how);
    # test_sim_config keeps these defaults equal to the shipped file's
    drift_xy_m_per_sqrt_s: Range = Range(0.0045, 0.0135)
    drift_yaw_rad_per_sqrt_s: Range = Range(0.00225, 0.00675)
    loss_rate_per_min: Range = Range(1.0, 1.0)          # random tracking-loss episodes
    loss_duration_s: Range = Range(0.5, 2.0)            # each episode's length is drawn here
    loss_episodes: List[List[float]] = field(default_factory=list)  # scheduled [start_s, dur_s]


@dataclass
class MonitorConfig:
    rollover_tilt_deg: float = 90.0     # base_link's z axis this far from the vertical: rolled over


@dataclass
class ScalesConfig:
    """Ventral scales (frictional anisotropy), applied by sim/scales.py's ScaledPlant only."""
    enabled: bool = False
    forward_friction: float = 0.7       # Coulomb coefficient, link sliding towards its head end
    backward_friction: float = 1.5      # sliding towards its tail end
    lateral_friction: float = 1.2       # sliding sideways
    regularisation_m_s: float = 0.02    # friction ramps up over this speed (no stick-slip chatter)


@dataclass
class DisturbanceConfig:
    time_s: float
    link: str                                    # a body: base_link (head segment), link_1 ...
    force_n: Optional[List[float]] = None        # world frame, at the link's centre of mass
    torque_nm: Optional[List[float]] = None      # world frame
    duration_s: float = 0.1


_SECTIONS = {"physics": PhysicsConfig, "servo": ServoConfig, "mocap": MocapConfig,
             "vio": VioConfig, "monitor": MonitorConfig, "scales": ScalesConfig, "depth_noise": DepthNoiseConfig,
             "imu": ImuConfig}


@dataclass
class SimConfig:
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    servo: ServoConfig = field(default_factory=ServoConfig)
    mocap: MocapConfig = field(default_factory=MocapConfig)
    vio: VioConfig = field(default_factory=VioConfig)
    monitor: MonitorConfig = field(default_factory=MonitorConfig)
    scales: ScalesConfig = field(default_factory=ScalesConfig)
    depth_noise: DepthNoiseConfig = field(default_factory=DepthNoiseConfig)
    imu: ImuConfig = field(default_factory=ImuConfig)
    disturbances: List[DisturbanceConfig] = field(default_factory=list)
    # config/tracker.yaml keys overridden for the simulated robot (snake_autonomy.missions.load_defaults)
    tracker: dict = field(default_factory=dict)
    base_dir: Path = Path(".")      # where relative file names (vio.calibration) are resolved

    @classmethod
    def from_yaml(cls, path) -> "SimConfig":
        path = Path(path)
        raw = load_yaml_file(path) or {}
        return cls.from_dict(raw, base_dir=path.parent)

    @classmethod
    def from_dict(cls, raw: dict, base_dir=Path(".")) -> "SimConfig":
        errors: List[str] = []
        if not isinstance(raw, dict):
            raise ValueError(f"sim config: expected a mapping, got {raw!r}")
        out = cls(base_dir=Path(base_dir))
        for key, value in raw.items():
            if key in _SECTIONS:
                setattr(out, key, _parse_section(key, _SECTIONS[key], value, errors))
            elif key == "disturbances":
                out.disturbances = _parse_disturbances(value, errors)
            elif key == "tracker":
                out.tracker = _parse_tracker(value, errors)
            else:
                errors.append(f"{key}: unknown key (expected one of "
                              f"{', '.join(list(_SECTIONS) + ['disturbances', 'tracker'])})")
        errors += out.problems()
        if errors:
            raise ValueError("sim config:\n  " + "\n  ".join(errors))
        return out

    def problems(self) -> List[str]:
        """Every invalid value, each naming its key."""
        errs = []
        p, s, m, v = self.physics, self.servo, self.mocap, self.vio

        def positive(key, value):
            lo = value.lo if isinstance(value, Range) else value
            if not lo > 0:
                errs.append(f"{key}: must be > 0, got {_show(value)}")

        def non_negative(key, value):
            lo = value.lo if isinstance(value, Range) else value
            if not lo >= 0:
                errs.append(f"{key}: must be >= 0, got {_show(value)}")

        positive("physics.timestep_s", p.timestep_s)
        if p.integrator not in ("implicitfast", "implicit", "RK4", "Euler"):
            errs.append(f"physics.integrator: unknown integrator {p.integrator!r}")
        if p.cone not in ("elliptic", "pyramidal"):
            errs.append(f"physics.cone: expected elliptic or pyramidal, got {p.cone!r}")
        positive("physics.floor_friction", p.floor_friction)
        non_negative("physics.torsional_friction", p.torsional_friction)
        non_negative("physics.rolling_friction_m", p.rolling_friction_m)
        if p.contact_timeconst_s < 2 * p.timestep_s:
            errs.append(f"physics.contact_timeconst_s: must be >= 2 timesteps "
                        f"({2 * p.timestep_s}), got {p.contact_timeconst_s}")
        positive("physics.contact_dampratio", p.contact_dampratio)
        positive("physics.solver_iterations", p.solver_iterations)
        non_negative("physics.start_height_m", p.start_height_m)
        if not 0.0 <= p.flat_belly_fraction <= 1.0:
            errs.append(f"physics.flat_belly_fraction: must be in [0, 1], got {p.flat_belly_fraction!r}")
        for key in ("torque_limit_nm", "speed_limit_rad_s", "kp_nm_per_rad",
                    "torque_constant_nm_per_a", "setpoint_period_s"):
            positive(f"servo.{key}", getattr(s, key))
        for key in ("kv_nm_s_per_rad", "armature_kg_m2", "damping_nm_s_per_rad",
                    "frictionloss_nm"):
            non_negative(f"servo.{key}", getattr(s, key))
        if s.setpoint_period_s < p.timestep_s:
            errs.append(f"servo.setpoint_period_s: must be >= physics.timestep_s "
                        f"({p.timestep_s}), got {s.setpoint_period_s}")
        if not 0 < self.monitor.rollover_tilt_deg <= 180:
            errs.append(f"monitor.rollover_tilt_deg: must be in (0, 180], got {self.monitor.rollover_tilt_deg}")
        for key in ("forward_friction", "backward_friction", "lateral_friction", "regularisation_m_s"):
            positive(f"scales.{key}", getattr(self.scales, key))
        positive("mocap.rate_hz", m.rate_hz)
        non_negative("mocap.position_noise_m", m.position_noise_m)
        non_negative("mocap.rotation_noise_rad", m.rotation_noise_rad)
        positive("vio.rate_hz", v.rate_hz)
        non_negative("vio.latency_s", v.latency_s)
        for key in ("position_noise_m", "rotation_noise_rad", "drift_xy_m_per_sqrt_s",
                    "drift_yaw_rad_per_sqrt_s", "loss_rate_per_min"):
            non_negative(f"vio.{key}", getattr(v, key))
        positive("vio.loss_duration_s", v.loss_duration_s)
        for i, ep in enumerate(v.loss_episodes):
            if (not isinstance(ep, (list, tuple)) or len(ep) != 2
                    or not all(isinstance(x, (int, float)) for x in ep) or ep[1] <= 0):
                errs.append(f"vio.loss_episodes[{i}]: expected [start_s, duration_s > 0], "
                            f"got {ep!r}")
        errs += self.depth_noise.problems("depth_noise")
        errs += self.imu.problems("imu")
        for i, d in enumerate(self.disturbances):
            if (d.force_n is None) == (d.torque_nm is None):
                errs.append(f"disturbances[{i}]: give exactly one of force_n, torque_nm")
            for key in ("force_n", "torque_nm"):
                vec = getattr(d, key)
                if vec is not None and (len(vec) != 3
                                        or not all(isinstance(x, (int, float)) for x in vec)):
                    errs.append(f"disturbances[{i}].{key}: expected 3 numbers, got {vec!r}")
            positive(f"disturbances[{i}].duration_s", d.duration_s)
            non_negative(f"disturbances[{i}].time_s", d.time_s)
        return errs

    def with_flat_belly(self, fraction: float) -> "SimConfig":
        """This configuration with physics.flat_belly_fraction set (the nav runs' and gait maps' plant
        option, sim/mjcf.py)."""
        return dataclasses.replace(self, physics=dataclasses.replace(self.physics,
                                                                     flat_belly_fraction=float(fraction)))

    def calibration_path(self) -> Path:
        path = Path(self.vio.calibration)
        return path if path.is_absolute() else self.base_dir / path

    def draw(self, seed: int, randomize: bool = True, num_joints: int = 11) -> "SimParams":
        """Concrete values for one run. randomize=False: midpoints, noise streams still seeded."""
        params = SimParams(seed=int(seed), config=self)

        def pick(rng_name, rng_range, size=None):
            if not randomize:
                return rng_range.nominal if size is None else np.full(size, rng_range.nominal)
            return rng_range.draw(params.rng("draw." + rng_name), size)

        params.floor_friction = float(pick("floor_friction", self.physics.floor_friction))
        params.kp_nm_per_rad = np.asarray(pick("kp", self.servo.kp_nm_per_rad, num_joints), float)
        params.kv_nm_s_per_rad = np.asarray(pick("kv", self.servo.kv_nm_s_per_rad, num_joints),
                                            float)
        m, v = self.mocap, self.vio
        params.mocap_position_noise_m = float(pick("mocap_pos", m.position_noise_m))
        params.mocap_rotation_noise_rad = float(pick("mocap_rot", m.rotation_noise_rad))
        params.vio_position_noise_m = float(pick("vio_pos", v.position_noise_m))
        params.vio_rotation_noise_rad = float(pick("vio_rot", v.rotation_noise_rad))
        params.vio_drift_xy_m_per_sqrt_s = float(pick("vio_drift_xy", v.drift_xy_m_per_sqrt_s))
        params.vio_drift_yaw_rad_per_sqrt_s = float(pick("vio_drift_yaw",
                                                         v.drift_yaw_rad_per_sqrt_s))
        params.vio_loss_rate_per_min = float(pick("vio_loss_rate", v.loss_rate_per_min))
        return params


def servo_torque_limit_nm(path=None) -> float:
    """The servos' torque limit (N m) of config/sim.yaml (or PATH): also the FBSR planner's torque bound."""
    return SimConfig.from_yaml(path or config_path("sim.yaml")).servo.torque_limit_nm


@dataclass
class SimParams:
    """The values of one simulation run (one seed): what the plant and sensors are built from."""
    seed: int
    config: SimConfig
    floor_friction: float = 0.0
    kp_nm_per_rad: np.ndarray = None
    kv_nm_s_per_rad: np.ndarray = None
    mocap_position_noise_m: float = 0.0
    mocap_rotation_noise_rad: float = 0.0
    vio_position_noise_m: float = 0.0
    vio_rotation_noise_rad: float = 0.0
    vio_drift_xy_m_per_sqrt_s: float = 0.0
    vio_drift_yaw_rad_per_sqrt_s: float = 0.0
    vio_loss_rate_per_min: float = 0.0

    def rng(self, stream: str) -> np.random.Generator:
        """A generator for one named consumer: the same (seed, name) gives the same numbers."""
        return np.random.default_rng([self.seed, zlib.crc32(stream.encode())])

    def summary(self) -> dict:
        out = {k: v for k, v in dataclasses.asdict(self).items() if k != "config"}
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in out.items()}


def _show(value):
    return f"[{value.lo}, {value.hi}]" if isinstance(value, Range) else repr(value)


# Every number of sim.yaml is finite and within +-MAX_VALUE (SI units: no simulated quantity comes
# near it; a 1e308 friction or timestep is refused here with its key, before MuJoCo sees it).
MAX_VALUE = 1e6


def _parse_value(key, kind, value, errors):
    numbers = value if isinstance(value, list) and kind is Range else [value]
    for v in numbers:
        if isinstance(v, (int, float)) and not isinstance(v, bool) and not (math.isfinite(v) and abs(v) <= MAX_VALUE):
            errors.append(f"{key}: must be finite and within +-{MAX_VALUE:g}, got {v!r}")
            return None
    if kind is Range:
        if isinstance(value, bool):
            errors.append(f"{key}: expected a number or [lo, hi], got {value!r}")
            return None
        if isinstance(value, (int, float)):
            return Range(float(value), float(value))
        if (isinstance(value, list) and len(value) == 2
                and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)):
            if value[0] > value[1]:
                errors.append(f"{key}: lo must be <= hi, got {value!r}")
                return None
            return Range(float(value[0]), float(value[1]))
        errors.append(f"{key}: expected a number or [lo, hi], got {value!r}")
        return None
    if kind is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
    elif kind is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif kind is bool:
        if isinstance(value, bool):
            return value
    elif kind is str:
        if isinstance(value, str):
            return value
    else:   # lists
        if isinstance(value, list):
            return value
    errors.append(f"{key}: expected {getattr(kind, '__name__', 'a list')}, got {value!r}")
    return None


def _parse_section(name, cls, raw, errors):
    out = cls()
    if raw is None:
        return out
    if not isinstance(raw, dict):
        errors.append(f"{name}: expected a mapping, got {raw!r}")
        return out
    kinds = {f.name: f.type for f in dataclasses.fields(cls)}
    for key, value in raw.items():
        if key not in kinds:
            errors.append(f"{name}.{key}: unknown key (expected one of {', '.join(kinds)})")
            continue
        kind = kinds[key]
        kind = list if getattr(kind, "__origin__", None) is list else kind
        parsed = _parse_value(f"{name}.{key}", kind, value, errors)
        if parsed is not None:
            setattr(out, key, parsed)
    return out


def _parse_tracker(raw, errors):
    """The tracker: section: overrides of config/tracker.yaml, checked by the mission loader."""
    if raw is None:
        return {}
    try:
        load_defaults(overrides=raw, overrides_source="tracker")
    except MissionError as exc:
        errors.extend(f"tracker.{p}" if not p.startswith("tracker") else p for p in exc.problems)
        return {}
    return dict(raw)


def _parse_disturbances(raw, errors):
    out = []
    if raw is None:
        return out
    if not isinstance(raw, list):
        errors.append(f"disturbances: expected a list, got {raw!r}")
        return out
    names = {f.name for f in dataclasses.fields(DisturbanceConfig)}
    for i, item in enumerate(raw):
        if not isinstance(item, dict) or "time_s" not in item or "link" not in item:
            errors.append(f"disturbances[{i}]: expected a mapping with time_s and link, "
                          f"got {item!r}")
            continue
        unknown = set(item) - names
        if unknown:
            errors.append(f"disturbances[{i}]: unknown keys {sorted(unknown)}")
            continue
        out.append(DisturbanceConfig(**item))
    return out
