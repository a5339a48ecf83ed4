"""Shared fixtures: the shipped scenario S1, loaded once per test session; the
Hypothesis profiles."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings

matplotlib.use("Agg")

# The suite is deterministic: property tests draw the same cases on every run (a red CI
# run is a regression, never a newly drawn case). HYPOTHESIS_PROFILE=explore draws new
# random cases on every run, to hunt for bugs; every failure prints its seed.
settings.register_profile("default", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

ROOT = Path(__file__).resolve().parents[1]
S1_PATH = ROOT / "data" / "scenarios" / "s1.yaml"


@pytest.fixture(scope="session")
def s1_resources():  # type: ignore[no-untyped-def]
    from mrcomm.run.resources import ScenarioResources

    return ScenarioResources.load(S1_PATH)
