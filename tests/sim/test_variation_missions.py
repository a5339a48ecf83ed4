"""Run-to-run variation in whole missions (``robot.variation``): reproducible per seed,
different between seeds, the default profile is the robots of earlier versions (see
also the goldens), and bad values are one-line errors."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from mrcomm.errors import InputError
from mrcomm.experiment.schema import load_experiment
from mrcomm.run.config import make_config, param_assignments
from mrcomm.sim.mission import Mission
from tests.cli.test_run_cli import mrcomm
from tests.conftest import S1_PATH


def outcome(resources: Any, seed: int, profile: str | None) -> dict[str, Any]:
    params = {} if profile is None else {"robot": {"variation": profile}}
    config = make_config(None, scenario=S1_PATH, network="wlan", seed=seed, params=params)
    mission = Mission(config, resources)
    result = mission.run()
    return {
        "mission": result.mission,
        "robots": result.robots,
        "trajectory": [b.true_pose for b in mission.bases.values()],
        "jumps": {r: b.localisation_jumps for r, b in mission.bases.items()},
        "delays": {r: b.start_delay for r, b in mission.bases.items()},
        "factors": {r: b.speed_factor for r, b in mission.bases.items()},
    }


def test_realistic_is_reproducible(s1_resources) -> None:  # type: ignore[no-untyped-def]
    assert outcome(s1_resources, 3, "realistic") == outcome(s1_resources, 3, "realistic")


def test_realistic_varies_between_seeds(s1_resources) -> None:  # type: ignore[no-untyped-def]
    seeds = (1, 2, 3, 4)
    times = [
        outcome(s1_resources, s, "realistic")["mission"]["execution_phase_time"] for s in seeds
    ]
    plain = [outcome(s1_resources, s, None)["mission"]["execution_phase_time"] for s in seeds]
    assert len(set(times)) == 4
    # Several seconds apart, where the deterministic robots differ by about one.
    assert max(times) - min(times) > 3.0
    assert max(times) - min(times) > max(plain) - min(plain)


def test_realistic_draws_are_what_the_bases_use(s1_resources) -> None:  # type: ignore[no-untyped-def]
    got = outcome(s1_resources, 5, "realistic")
    assert len(set(got["factors"].values())) == len(got["factors"])  # each robot its own
    assert all(0.0 <= d <= 4.0 for d in got["delays"].values())
    plain = outcome(s1_resources, 5, None)
    assert set(plain["factors"].values()) == {1.0}
    assert set(plain["delays"].values()) == {0.0}
    assert set(plain["jumps"].values()) == {0}


def test_none_is_the_default_and_leaves_the_configuration_alone(s1_resources) -> None:  # type: ignore[no-untyped-def]
    explicit = make_config(None, scenario=S1_PATH, params={"robot": {"variation": "none"}})
    assert explicit.params == {}  # so configuration ids and stored options are unchanged
    assert outcome(s1_resources, 2, "none") == outcome(s1_resources, 2, None)
    realistic = make_config(None, scenario=S1_PATH, params={"robot": {"variation": "realistic"}})
    assert param_assignments(realistic) == ['robot.variation="realistic"']


@pytest.mark.parametrize(
    ("robot", "field"),
    [
        ({"variation": "bogus"}, "robot.variation"),
        ({"speed_sigma": -0.1}, "robot.speed_sigma"),
        ({"jump_rate": float("nan")}, "robot.jump_rate"),
        ({"speed_sigm": 0.1}, "robot.speed_sigm"),
    ],
)
def test_bad_values_name_the_field(robot: dict[str, Any], field: str) -> None:
    with pytest.raises(InputError) as err:
        make_config(None, scenario=S1_PATH, params={"robot": robot})
    assert err.value.field == field


@pytest.mark.parametrize(
    ("setting", "expected"),
    [
        ("robot.variation=bogus", "--set robot.variation: "),
        ("robot.speed_sigma=-1", "--set robot.speed_sigma: "),
        ("robot.start_delay_max=nan", "--set robot.start_delay_max: "),
    ],
)
def test_bad_cli_value_is_one_line_exit_2(setting: str, expected: str) -> None:
    done = mrcomm("run", str(S1_PATH), "--set", setting)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert expected in done.stderr


def test_a_study_sweeps_the_profile(tmp_path: Path) -> None:
    schema = tmp_path / "study.yaml"
    schema.write_text(
        f"scenario: {S1_PATH}\nrepetitions: 1\n"
        "factors:\n  robot.variation: [none, realistic]\n"
        "params:\n  robot.speed_sigma: 0.1\n"
    )
    runs = load_experiment(schema).runs()
    assert [r.config.params for r in runs] == [
        {"robot": {"speed_sigma": 0.1}},
        {"robot": {"variation": "realistic", "speed_sigma": 0.1}},
    ]
    assert runs[0].config_id != runs[1].config_id
    schema.write_text(
        f"scenario: {S1_PATH}\nrepetitions: 1\nfactors:\n  robot.variation: [none, bogus]\n"
    )
    with pytest.raises(InputError) as err:
        load_experiment(schema)
    assert err.value.field == "factors.robot.variation"
