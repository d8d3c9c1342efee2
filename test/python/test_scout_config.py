"""config/scout.yaml's checks (planning/fbsr/config.py): every value finite, gains, margins, lengths
and counts in their ranges, every problem listed at once with its key and value, the file named."""
import pytest

from snake_autonomy.planning.fbsr.config import ConfigError, ScoutConfig, default_path


def test_the_provided_file_is_valid():
    cfg = ScoutConfig.from_yaml(default_path())
    assert cfg.planner.k1 > 0 and "unified_snake" in cfg.robots


def test_every_problem_is_listed_with_its_key_its_value_and_the_file(tmp_path):
    path = tmp_path / "scout.yaml"
    path.write_text("planner:\n  k1: .nan\n  k3: -1\n  margin_m: .inf\n  target_tol_m: 0\n"
                    "robots:\n  cobra:\n    yaw_body_deg: .nan\n    max_active: 6\n")
    with pytest.raises(ConfigError) as err:
        ScoutConfig.from_yaml(path)
    text = str(err.value)
    assert text.startswith(f"{path}: ") and "\n" not in text
    for words in ("planner.k1: must be a finite number, got nan", "planner.k3: must be >= 0, got -1.0",
                  "planner.margin_m: must be a finite number, got inf", "planner.target_tol_m: must be > 0, got 0.0",
                  "robots.cobra.yaw_body_deg: must be a finite number, got nan"):
        assert words in text, (words, text)
    assert text.count("planner.k1") == 1        # a NaN is reported once, not again as "< 0"


@pytest.mark.parametrize("key, value, words", [
    ("k2", float("nan"), "planner.k2: must be a finite number, got nan"),
    ("ks_per_m2", float("-inf"), "planner.ks_per_m2: must be a finite number, got -inf"),
    ("joint_margin_deg", 90, "planner.joint_margin_deg: must be at most 45, got 90.0"),
    ("margin_m", 2, "planner.margin_m: must be at most 0.5 m, got 2.0"),
    ("self_collision_margin_m", -0.001, "planner.self_collision_margin_m: must be >= 0, got -0.001"),
    ("self_collision_margin_m", 0.2, "planner.self_collision_margin_m: must be at most 0.05 m, got 0.2"),
    ("k_self_collision_per_m2", 0, "planner.k_self_collision_per_m2: must be > 0, got 0.0"),
    ("self_collision_push_m", 1, "planner.self_collision_push_m: must be at most 0.1 m, got 1.0"),
    ("max_restarts", 10 ** 9, "planner.max_restarts: must be at most 100, got 1000000000"),
    ("cost_samples", 10 ** 8, "planner.cost_samples: must be at most 200, got 100000000"),
    ("head_height_tol_m", 0, "planner.head_height_tol_m: must be > 0, got 0.0"),
    ("pipe_clearance_m", -0.01, "planner.pipe_clearance_m: must be >= 0, got -0.01"),
    ("pipe_clearance_m", 0.5, "planner.pipe_clearance_m: must be at most 0.1 m, got 0.5"),
])
def test_a_bad_planner_value_is_refused_naming_the_key(key, value, words):
    with pytest.raises(ConfigError) as err:
        ScoutConfig.from_dict({"planner": {key: value}})
    assert words in str(err.value) and str(err.value).startswith("scout config: ")
