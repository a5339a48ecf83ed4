"""Larger teams give the same results as before the simulator's speed work (recorded
with ``python -m tests.golden.team_golden --write`` on the code before it)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from .team_golden import CASES, TEAM_GOLDEN_FILE, run_team_case

GOLDEN: dict[str, Any] = json.loads(TEAM_GOLDEN_FILE.read_text())


@pytest.mark.slow
@pytest.mark.parametrize(("name", "scenario", "options"), CASES, ids=[c[0] for c in CASES])
def test_team_run_is_identical_to_the_recorded_one(
    name: str, scenario: Path, options: dict[str, Any]
) -> None:
    assert run_team_case(scenario, options) == GOLDEN[name]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "scenario", "options"),
    [c for c in CASES if c[0].startswith("s2")],
    ids=lambda c: c if isinstance(c, str) else "",
)
def test_a_team_view_on_arrays_gives_the_recorded_run(
    name: str, scenario: Path, options: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The bus's store of latest poses (positions and heard times as arrays, kept for
    teams of at least ``KEEP_LATEST_FROM`` endpoints, e.g. 1000 robots), read by each
    view through its mate table, leaves every result as it was: here with the store
    whatever the team's size, NB and LF."""
    from mrcomm.agents import team_view
    from mrcomm.net import inprocess

    monkeypatch.setattr(inprocess, "KEEP_LATEST_FROM", 1)
    calls = 0
    near = team_view._MateTable.near

    def counted(self: team_view._MateTable, x: float, y: float, reach: float) -> list[Any]:
        nonlocal calls
        calls += 1
        return near(self, x, y, reach)

    monkeypatch.setattr(team_view._MateTable, "near", counted)
    assert run_team_case(scenario, options) == GOLDEN[name]
    assert calls > 1000  # the arrays answered
