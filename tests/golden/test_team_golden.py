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
