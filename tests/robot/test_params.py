"""RobotParams: defaults, validation and loading from a mapping."""

from __future__ import annotations

import dataclasses

import pytest

from mrcomm.errors import InputError
from mrcomm.robot.params import RobotParams


def test_defaults_are_turtlebot2() -> None:
    p = RobotParams()
    assert p.radius == pytest.approx(0.18)
    assert p.max_v == pytest.approx(0.5)
    assert p.max_w == pytest.approx(1.5)
    assert p.inflation_radius == pytest.approx(p.radius + p.inflation_margin)
    assert p.sensing_range == pytest.approx(2.0)
    assert p.reverse_distance == pytest.approx(0.5)


def test_from_mapping_overrides_and_keeps_defaults() -> None:
    p = RobotParams.from_mapping({"max_v": 0.3, "stuck_timeout": 4})
    assert p.max_v == pytest.approx(0.3)
    assert p.stuck_timeout == 4
    assert p.radius == RobotParams().radius


def test_unknown_key_names_file_field_and_suggestion() -> None:
    with pytest.raises(InputError) as err:
        RobotParams.from_mapping({"max_vel": 1.0}, file="robot.yaml")
    text = str(err.value)
    assert text.startswith("robot.yaml: max_vel:")
    assert "did you mean 'max_v'" in text
    assert "\n" not in text


@pytest.mark.parametrize(
    ("key", "value"),
    [("radius", -0.1), ("max_v", 0.0), ("goal_tolerance", "far"), ("lookahead", float("nan"))],
)
def test_bad_values_are_input_errors(key: str, value: object) -> None:
    with pytest.raises(InputError) as err:
        RobotParams.from_mapping({key: value}, file="robot.yaml")
    assert err.value.field == key
    assert err.value.file == "robot.yaml"


def test_params_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        RobotParams().radius = 1.0  # type: ignore[misc]
