"""The bundled data by name: scenarios, experiments and traces resolve to the data tree;
a path or an unknown name stays as given; a copied scenario loads the same mission from
its own directory, comments kept; a non-empty target is refused before anything is
written."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrcomm.bundled import bundled, data_file, data_root, resolve
from mrcomm.errors import InputError
from mrcomm.world.scenario import load_scenario
from mrcomm.world.scenario_copy import copy_scenario
from tests.conftest import ROOT, S1_PATH


def test_names_resolve_to_the_data_tree() -> None:
    assert data_root() == ROOT / "data"
    assert resolve(Path("s1"), "scenario") == S1_PATH
    assert resolve(Path("s2"), "scenario") == ROOT / "data/scenarios/s2/s2.yaml"
    assert resolve(Path("demo"), "experiment") == ROOT / "data/experiments/demo.yaml"
    assert resolve(Path("s1_synthetic_esd"), "trace").name == "s1_synthetic_esd.csv"
    assert set(bundled("scenario")) == {"s1", "s2", "s3", "s4", "campus1000"}
    assert data_file("signal/default_model.json").is_file()


def test_paths_and_unknown_names_stay_as_given(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s1").mkdir()  # a local directory wins over the bundled name
    assert resolve(Path("s1"), "scenario") == Path("s1")
    for given in ("nope", "s1.yaml", "x/s2"):
        assert resolve(Path(given), "scenario") == Path(given)
    with pytest.raises(InputError, match="bundled file not found"):
        data_file("signal/missing.json")


def test_a_copied_scenario_is_the_same_mission(tmp_path: Path) -> None:
    copied = copy_scenario(S1_PATH, tmp_path / "mine")
    assert sorted(p.name for p in copied.parent.iterdir()) == [
        "office.pgm", "office.yaml", "s1.yaml", "s1_tasks.yaml"
    ]  # fmt: skip
    text = copied.read_text()
    assert "map: office.yaml" in text and text.startswith("# Scenario S1")
    original, copy = load_scenario(S1_PATH), load_scenario(copied)
    assert (copy.robots, copy.tasks, copy.assigner) == (
        original.robots,
        original.tasks,
        original.assigner,
    )
    assert (copy.grid.occupied == original.grid.occupied).all()


def test_copy_refuses_a_full_directory(tmp_path: Path) -> None:
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "keep.txt").write_text("mine")
    with pytest.raises(InputError, match="not an empty directory"):
        copy_scenario(S1_PATH, tmp_path / "full")
    assert [p.name for p in (tmp_path / "full").iterdir()] == ["keep.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["full"]  # no staging left
