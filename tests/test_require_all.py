"""``MRCOMM_REQUIRE_ALL=1`` (set by ``.ci/run``) turns a skip for want of something
``make test`` installs into a failed session: shown on the console's real browser test,
run where chromium-driver cannot be found (an empty PATH), in parallel as make test
runs it, and without the variable (skipped, green) for contrast."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.conftest import ROOT

BROWSER_TEST = "tests/console/test_console_browser.py"


def _pytest_without_tools(tmp_path: Path, require_all: bool) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("MRCOMM_", "PYTEST_"))}
    env["PATH"] = str(tmp_path)  # an empty directory: no chromium, no chromedriver
    if require_all:
        env["MRCOMM_REQUIRE_ALL"] = "1"
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-n", "2", "-p", "no:cacheprovider", BROWSER_TEST],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300,
    )  # fmt: skip


def test_a_missing_tool_fails_the_run_when_everything_is_required(tmp_path: Path) -> None:
    required = _pytest_without_tools(tmp_path, require_all=True)
    assert required.returncode == 1, required.stdout + required.stderr
    assert "MRCOMM_REQUIRE_ALL=1" in required.stdout
    assert "chromium, chromedriver not installed" in required.stdout


def test_without_the_variable_the_same_run_skips(tmp_path: Path) -> None:
    relaxed = _pytest_without_tools(tmp_path, require_all=False)
    assert relaxed.returncode in (0, 5), relaxed.stdout + relaxed.stderr  # 5: none collected
    assert "MRCOMM_REQUIRE_ALL" not in relaxed.stdout


def test_ci_requires_everything() -> None:
    ci = (ROOT / ".ci" / "run").read_text()
    assert "MRCOMM_REQUIRE_ALL=1" in ci
    make = (ROOT / "Makefile").read_text()
    assert "MRCOMM_REQUIRE_ALL" in make  # the ROS 2 environment that could not be built
