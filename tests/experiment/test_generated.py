"""Team size as a factor: a schema whose scenario is a generator spec expands into one
generated scenario per team size, made once next to the schema and reused; a spec
that is wrong or a directory that holds something else is refused in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrcomm.errors import InputError
from mrcomm.experiment.schema import load_experiment

SPEC = """name: scale
scenario:
  generate: {{map: grid, size: 20x15, start: scattered, assigner: base, seed: 1}}
  robots: {robots}
  {tasks}
repetitions: 1
factors: {{network: wlan, behaviour: nb, spl: [0, 25]}}
"""


def write(tmp_path: Path, robots: str = "[3, 6]", tasks: str = "tasks_per_robot: 2") -> Path:
    path = tmp_path / "scale.yaml"
    path.write_text(SPEC.format(robots=robots, tasks=tasks))
    return path


def test_one_scenario_per_team_size_made_once(tmp_path: Path) -> None:
    schema = write(tmp_path)
    experiment = load_experiment(schema)
    sizes = {c.scenario_name: c for c in experiment.configurations}
    assert sorted(sizes) == ["grid-n3", "grid-n6"]
    assert len(experiment.configurations) == 4  # 2 sizes x 2 SPL levels
    assert {c.label for c in experiment.configurations} >= {"grid-n3_WLAN_NB_SPL0"}
    made = sorted((tmp_path / "generated").iterdir())
    assert [p.name for p in made] == [
        "grid-20x15-scattered-base-seed1-n3-t6",
        "grid-20x15-scattered-base-seed1-n6-t12",
    ]
    stamp = (made[0] / "grid-n3.yaml").stat().st_mtime_ns
    again = load_experiment(schema)  # reused, not made again
    assert (made[0] / "grid-n3.yaml").stat().st_mtime_ns == stamp
    assert [c.config_id for c in again.configurations] == [
        c.config_id for c in experiment.configurations
    ]


def test_a_directory_holding_another_scenario_is_refused(tmp_path: Path) -> None:
    schema = write(tmp_path, robots="[3]")
    load_experiment(schema)
    scenario = next((tmp_path / "generated").iterdir()) / "grid-n3.yaml"
    scenario.write_text(scenario.read_text().replace("--seed 1", "--seed 2", 1))
    with pytest.raises(InputError, match="holds another scenario than the spec makes"):
        load_experiment(schema)


@pytest.mark.parametrize("target", ["grid-n3.yaml", "grid-n3_tasks.yaml", "MANIFEST.sha256"])
def test_a_hand_edited_generated_scenario_is_refused(tmp_path: Path, target: str) -> None:
    """Its header unchanged, a task moved: the cache was once used silently, storing runs
    of two different scenarios under one configuration id."""
    schema = write(tmp_path, robots="[3]")
    load_experiment(schema)
    folder = next((tmp_path / "generated").iterdir())
    edited = folder / target
    assert edited.exists(), sorted(p.name for p in folder.iterdir())
    edited.write_text(edited.read_text() + "\n# edited\n")
    with pytest.raises(InputError, match="was changed since it was made"):
        load_experiment(schema)


@pytest.mark.parametrize(
    ("robots", "tasks", "message"),
    [
        ("[3, 3]", "tasks: 6", "a team size is given twice"),
        ("[3]", "tasks: 6\n  tasks_per_robot: 2", "give tasks or tasks_per_robot"),
        ("[3]", "", "give tasks or tasks_per_robot"),
        ("[500]", "tasks: 6", "team size 500: --robots: 500 robots do not fit"),
        ("[]", "tasks: 6", "robots"),
    ],
)
def test_bad_specs(tmp_path: Path, robots: str, tasks: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        load_experiment(write(tmp_path, robots=robots, tasks=tasks))
