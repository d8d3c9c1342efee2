"""config/sim.yaml loads; a bad config names every bad key and value at once."""
import dataclasses

import pytest

from snake_autonomy.sim.config import Range, SimConfig


def test_shipped_config_loads(root):
    cfg = SimConfig.from_yaml(root / "config" / "sim.yaml")
    assert cfg.servo.torque_limit_nm == 9.9
    assert isinstance(cfg.physics.floor_friction, Range)
    assert cfg.calibration_path() == root / "config" / "camera.yaml"
    assert cfg.calibration_path().is_file()


def test_the_code_defaults_are_the_shipped_configs_values(root):
    """SimConfig() (what a run without sim.yaml, and WorldSpec's default, simulate) is config/sim.yaml:
    a refit of the file (the VIO drift's x2.25) must reach the code's defaults too."""
    shipped = dataclasses.asdict(SimConfig.from_yaml(root / "config" / "sim.yaml"))
    defaults = dataclasses.asdict(SimConfig())
    shipped.pop("base_dir"), defaults.pop("base_dir")        # where the file lies, not a value of it
    differ = [f"{section}.{key}: code {value!r}, sim.yaml {shipped[section][key]!r}"
              for section, values in defaults.items() if isinstance(values, dict)
              for key, value in values.items() if shipped[section][key] != value]
    differ += [f"{k}: code {v!r}, sim.yaml {shipped[k]!r}" for k, v in defaults.items()
               if not isinstance(v, dict) and shipped[k] != v]
    assert not differ, "; ".join(differ)


def test_every_problem_is_listed():
    raw = {
        "physics": {"timestep_s": -1, "bogus": 1, "floor_friction": [2, 1], "cone": "round"},
        "servo": {"kp_nm_per_rad": "stiff"},
        "vio": {"loss_episodes": [[1]]},
        "disturbances": [{"time_s": 1, "link": "link_3"},
                         {"time_s": 1, "link": "link_3", "force_n": [1, 2]}],
        "extra": {},
    }
    with pytest.raises(ValueError) as err:
        SimConfig.from_dict(raw)
    text = str(err.value)
    for expected in ("physics.bogus: unknown key",
                     "physics.floor_friction: lo must be <= hi, got [2, 1]",
                     "physics.timestep_s: must be > 0, got -1.0",
                     "physics.cone: expected elliptic or pyramidal, got 'round'",
                     "servo.kp_nm_per_rad: expected a number or [lo, hi], got 'stiff'",
                     "vio.loss_episodes[0]: expected [start_s, duration_s > 0], got [1]",
                     "disturbances[0]: give exactly one of force_n, torque_nm",
                     "disturbances[1].force_n: expected 3 numbers, got [1, 2]",
                     "extra: unknown key"):
        assert expected in text


def test_random_streams_are_named(root):
    params = SimConfig.from_yaml(root / "config" / "sim.yaml").draw(seed=5)
    assert params.rng("a").normal() == params.rng("a").normal()
    assert params.rng("a").normal() != params.rng("b").normal()


def test_every_number_has_a_range(tmp_path):
    """A finite but absurd value (1e308) is refused with its key, like NaN."""
    from snake_autonomy.sim.config import SimConfig
    f = tmp_path / "sim.yaml"
    f.write_text("physics:\n  timestep_s: 1.0e+308\n  floor_friction: [0.5, .inf]\n")
    with pytest.raises(ValueError) as err:
        SimConfig.from_yaml(f)
    assert "physics.timestep_s: must be finite and within +-1e+06, got 1e+308" in str(err.value)
    assert "physics.floor_friction: must be finite and within +-1e+06, got inf" in str(err.value)
