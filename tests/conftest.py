"""Shared fixtures: the shipped scenario S1, loaded once per test session."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parents[1]
S1_PATH = ROOT / "data" / "scenarios" / "s1.yaml"


@pytest.fixture(scope="session")
def s1_world():  # type: ignore[no-untyped-def]
    from mrcomm.sim.world import SimWorld

    return SimWorld.load(S1_PATH)
