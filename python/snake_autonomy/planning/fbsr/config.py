"""config/scout.yaml: the planner's parameters and each robot's lying posture, validated.

Every problem is collected and reported at once, naming the key and the value; unknown keys are
refused.
"""
import dataclasses
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
    joint_margin_deg: float = 3.0
    max_restarts: int = 8
    max_shift_replans: int = 4
    shift_restarts: int = 2
    max_backtracks: int = 4
    max_final_cycles: int = 2
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
        for key in ("stage_duration_s", "sample_period_s", "k2", "ks_per_m2", "k_out_per_m2"):
            if not getattr(p, key) > 0:
                out.append(f"planner.{key}: must be > 0, got {getattr(p, key)}")
        for key in ("k1", "k3", "k_torque", "k_wall_per_m2", "margin_m", "joint_margin_deg", "max_restarts",
                    "max_shift_replans", "shift_restarts", "max_backtracks",
                    "max_final_cycles", "head_height_tol_m",
                    "target_tol_m", "k1_step"):
            if getattr(p, key) < 0:
                out.append(f"planner.{key}: must be >= 0, got {getattr(p, key)}")
        if p.sample_period_s > 0.05:
            out.append(f"planner.sample_period_s: the contract allows at most 0.05, got {p.sample_period_s}")
        if p.cost_samples < 2:
            out.append(f"planner.cost_samples: must be >= 2, got {p.cost_samples}")
        for name, r in self.robots.items():
            if r.initial_active < 1:
                out.append(f"robots.{name}.initial_active: must be >= 1, got {r.initial_active}")
            if r.max_active < r.initial_active:
                out.append(f"robots.{name}.max_active: must be >= initial_active "
                           f"({r.initial_active}), got {r.max_active}")
        return out

    def posture(self, robot_name: str) -> RobotPosture:
        """The robot's section, or the defaults for a robot the file does not name."""
        return self.robots.get(robot_name, RobotPosture())


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
