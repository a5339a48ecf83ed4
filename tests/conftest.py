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


# With MRCOMM_REQUIRE_ALL=1 (.ci/run sets it), a skip for something `make test`
# installs (tests/needs.py) fails the session: CI is green only when everything ran.
_REQUIRED_SKIPS: list[str] = []


def _note_required_skip(report: pytest.CollectReport | pytest.TestReport) -> None:
    from tests.needs import is_required_skip

    if report.skipped and is_required_skip(report.longrepr):
        _REQUIRED_SKIPS.append(f"{report.nodeid}: {report.longrepr}")


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    _note_required_skip(report)


def pytest_collectreport(report: pytest.CollectReport) -> None:
    _note_required_skip(report)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    from tests.needs import REQUIRE_ALL

    if REQUIRE_ALL and _REQUIRED_SKIPS and not hasattr(session.config, "workerinput"):
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        if reporter is not None:
            title = "MRCOMM_REQUIRE_ALL=1: skipped for want of what make test installs"
            reporter.write_sep("=", title)
            for line in sorted(set(_REQUIRED_SKIPS)):
                reporter.write_line(line)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
