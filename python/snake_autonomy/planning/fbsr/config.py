"""config/scout.yaml: the planner's parameters and each robot's lying posture, validated.

Every problem is collected and reported at once, naming the key and the value; unknown keys are
refused. Every number must be finite; gains, margins, lengths and counts have ranges (problems()).
"""
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict

from snake_autonomy.paths import config_path

from ...safe_yaml import load_yaml_file


class ConfigError(ValueError):
    pass


@dataclass
class PlannerConfig:
    stage_duration_s: float = 3.0
    sample_period_s: float = 0.05
    cost_samples: int = 9
    k1: float = 1.0
    k2: float = 1.0
    k3: float = 0.5
    k_torque: float = 0.0
    k_wall_per_m2: float = 10000.0
    k1_step: float = 0.25
    ks_per_m2: float = 4.0e3
    k_out_per_m2: float = 1.0e3
    margin_m: float = 0.012
    self_collision_margin_m: float = 0.002
    self_collision_push_m: float = 0.025
    k_self_collision_per_m2: float = 1.0e5
    pipe_clearance_m: float = 0.0
    joint_margin_deg: float = 3.0
    max_restarts: int = 8
    max_shift_replans: int = 4
    shift_restarts: int = 2
    max_backtracks: int = 4
    max_final_cycles: int = 4
    head_height_tol_m: float = 0.005
    target_tol_m: float = 0.02


@dataclass
class RobotPosture:
    initial_active: int = 2
    max_active: int = 8
    pitch_offset_deg: float = 4.0
    yaw_body_deg: float = 8.0
    yaw_tail_deg: float = 75.0
    tail_curl_joints: int = 2


@dataclass
class ScoutConfig:
    planner: PlannerConfig = field(default_factory=PlannerConfig)
    robots: Dict[str, RobotPosture] = field(default_factory=dict)

    @classmethod
    def from_yaml(cls, path) -> "ScoutConfig":
        raw = load_yaml_file(path) or {}
        if not isinstance(raw, dict):
            raise ConfigError(f"{path}: expected a mapping of planner and robots, got a {type(raw).__name__}")
        return cls.from_dict(raw, str(path))

    @classmethod
    def from_dict(cls, raw: dict, where: str = "scout config") -> "ScoutConfig":
        errors = []
        unknown = set(raw) - {"planner", "robots"}
        errors += [f"{k}: unknown key" for k in sorted(unknown)]
        planner = _parse(PlannerConfig, raw.get("planner") or {}, "planner", errors)
        robots = {}
        for name, section in (raw.get("robots") or {}).items():
            robots[name] = _parse(RobotPosture, section or {}, f"robots.{name}", errors)
        cfg = cls(planner, robots)
        errors += cfg.problems()
        if errors:
            raise ConfigError(f"{where}: " + "; ".join(errors))
        return cfg

    def problems(self) -> list:
        out = []
        p = self.planner
        bad = _non_finite(p, "planner", out)
        ranges = (
            # key, lowest, whether the lowest itself is allowed, highest, unit of the message
            ("stage_duration_s", 0, False, 60, " s"), ("sample_period_s", 0, False, 0.05, " s"),
            ("cost_samples", 2, True, 200, ""),
            ("k1", 0, True, None, ""), ("k2", 0, False, None, ""), ("k3", 0, True, None, ""),
            ("k_torque", 0, True, None, ""), ("k_wall_per_m2", 0, True, None, ""),
            ("k1_step", 0, True, None, ""), ("ks_per_m2", 0, False, None, ""),
            ("k_out_per_m2", 0, False, None, ""),
            ("margin_m", 0, True, 0.5, " m"), ("joint_margin_deg", 0, True, 45, ""),
            ("self_collision_margin_m", 0, True, 0.05, " m"), ("self_collision_push_m", 0, True, 0.1, " m"),
            ("k_self_collision_per_m2", 0, False, None, ""), ("pipe_clearance_m", 0, True, 0.1, " m"),
            ("max_restarts", 0, True, 100, ""), ("max_shift_replans", 0, True, 100, ""),
            ("shift_restarts", 0, True, 100, ""), ("max_backtracks", 0, True, 100, ""),
            ("max_final_cycles", 0, True, 100, ""),
            ("head_height_tol_m", 0, False, 0.5, " m"), ("target_tol_m", 0, False, 0.5, " m"))
        for key, low, low_ok, high, unit in ranges:
            value = getattr(p, key)
            if key in bad:
                continue
            if value < low or (value == low and not low_ok):
                out.append(f"planner.{key}: must be {'>=' if low_ok else '>'} {low}, got {value}")
            elif high is not None and value > high:
                out.append(f"planner.{key}: must be at most {high}{unit}, got {value}")
        for name, r in self.robots.items():
            bad = _non_finite(r, f"robots.{name}", out)
            for key in ("pitch_offset_deg", "yaw_body_deg", "yaw_tail_deg"):
                if key not in bad and abs(getattr(r, key)) > 180:
                    out.append(f"robots.{name}.{key}: must be within +-180, got {getattr(r, key)}")
            if r.tail_curl_joints < 0:
                out.append(f"robots.{name}.tail_curl_joints: must be >= 0, got {r.tail_curl_joints}")
            if r.initial_active < 1:
                out.append(f"robots.{name}.initial_active: must be >= 1, got {r.initial_active}")
            if r.max_active < r.initial_active:
                out.append(f"robots.{name}.max_active: must be >= initial_active "
                           f"({r.initial_active}), got {r.max_active}")
        return out

    def posture(self, robot_name: str) -> RobotPosture:
        """The robot's section, or the defaults for a robot the file does not name."""
        return self.robots.get(robot_name, RobotPosture())


def _non_finite(section, prefix, out) -> set:
    """The float fields of `section` that are NaN or infinite, each reported in `out`."""
    bad = {f.name for f in dataclasses.fields(section)
           if isinstance(getattr(section, f.name), float) and not math.isfinite(getattr(section, f.name))}
    out += [f"{prefix}.{key}: must be a finite number, got {getattr(section, key)}" for key in sorted(bad)]
    return bad


def _parse(cls, raw, prefix, errors):
    if not isinstance(raw, dict):
        errors.append(f"{prefix}: expected a mapping, got {raw!r}")
        return cls()
    fields = {f.name: f for f in dataclasses.fields(cls)}
    values = {}
    for key, value in raw.items():
        if key not in fields:
            errors.append(f"{prefix}.{key}: unknown key")
            continue
        kind = type(fields[key].default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                (kind is int and not float(value).is_integer()):
            errors.append(f"{prefix}.{key}: expected {kind.__name__}, got {value!r}")
            continue
        values[key] = kind(value)
    return cls(**values)


def default_path() -> Path:
    return config_path("scout.yaml")
