import textwrap

import pytest

from snake_autonomy import _core


def test_cobra_loads(cobra_yaml):
    model = _core.RobotModel.from_yaml(cobra_yaml)
    assert model.num_joints == 11


def test_every_problem_is_listed(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(textwrap.dedent("""
        name: bad
        num_joints: 3
        axis_pattern: [pitch, roll]
        head_length_m: -0.1
        link_length_m: 0.1
        masses_kg: [1, 1, 1]
        joint_limits_deg: {lower: [0, 0, 10], upper: [10, 10, 5]}
        servos: {model: xh540_w270, ids: [1, 2, 3], directions: [1, 1, 1], zero_offsets_ticks: [0, 0, 0]}
        cpg: {mu: 10, gamma: 2, amplitude_limit_deg: 70}
        steering: {weights: [1], delta_limit_deg: 20, amplitude_min_deg: -70, amplitude_max_deg: 70}
    """))
    with pytest.raises(ValueError) as err:
        _core.RobotModel.from_yaml(str(bad))
    text = str(err.value)
    assert "axis_pattern[1]: unknown axis 'roll'" in text
    assert "head_length_m: must be a positive number, got -0.1" in text
    assert "masses_kg: expected 5 values, got 3" in text
    assert "joint_limits_deg[2]: lower must be < upper, got lower 10, upper 5" in text
