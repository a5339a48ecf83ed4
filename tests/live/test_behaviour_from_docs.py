"""A behaviour written only from the docs runs in simulation, live and ``mrcomm check``.

The example behaviour of docs/ARCHITECTURE.md ("An example, from this page alone") is
taken from the page itself, installed as a plugin (a distribution with its entry point
on ``PYTHONPATH``, found as pip's are; the live launcher's processes inherit it), and
run as a user would: the docs cannot drift from what works.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, S1_PATH

pytestmark = pytest.mark.slow

MARKER = "<!-- behaviour example: echo -->"


def example_source() -> str:
    page = (ROOT / "docs" / "ARCHITECTURE.md").read_text(encoding="utf-8")
    after = page.split(MARKER, 1)[1]
    block = after.split("```python\n", 1)[1].split("\n```", 1)[0]
    return block + "\n"


@pytest.fixture(scope="module")
def plugin(tmp_path_factory: pytest.TempPathFactory) -> Path:
    where = tmp_path_factory.mktemp("docs-plugin")
    (where / "echo_from_docs.py").write_text(example_source())
    info = where / "echo_from_docs-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: echo-from-docs\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        '[mrcomm.variants]\n"behaviour.echo" = echo_from_docs:SPEC\n'
    )
    return where


def mrcomm(plugin: Path, *args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(plugin)}
    code = "from mrcomm.cli.main import app; app()"
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=timeout,
        env=env,
    )  # fmt: skip


def test_the_example_runs_in_simulation(plugin: Path) -> None:
    done = mrcomm(plugin, "run", str(S1_PATH), "--behaviour", "echo", "--spl", "50",
                  "--set", "behaviour.echo_after=2", "--json")  # fmt: skip
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["config"]["params"] == {"behaviour": {"echo_after": 2.0}}
    assert result["mission"]["echoes"] >= 1  # its team metric
    sent = result["messages"]["task_status"]["sent"]
    assert sent == 7 + 3 + result["mission"]["echoes"]  # 7 successes, 3 agenda-completes


def test_the_example_passes_the_conformance_kit(plugin: Path) -> None:
    done = mrcomm(plugin, "check", "behaviour.echo", timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "assembly" in done.stdout


def test_the_example_runs_live(plugin: Path, tmp_path: Path) -> None:
    done = mrcomm(plugin, "live", str(S1_PATH), "--behaviour", "echo", "--speed", "10",
                  "--set", "behaviour.echo_after=2", "--record-dir", str(tmp_path / "live"),
                  "--json")  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout)
    assert result["config"]["mode"] == "live"
    assert result["mission"]["tasks_completed"] == 7
    assert result["mission"]["echoes"] >= 1
