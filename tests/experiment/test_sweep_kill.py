"""Kill test: a sweep killed with SIGKILL mid-way and restarted ends with every run
exactly once, and with the same rows as a sweep that was never interrupted."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from mrcomm.experiment.runner import execute_sweep, plan_sweep
from mrcomm.experiment.schema import load_experiment
from mrcomm.experiment.store import inspect_database
from tests.conftest import ROOT
from tests.experiment.helpers import MINI, snapshot, write_schema

MRCOMM = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]


def mrcomm(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*MRCOMM, *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=600
    )


@pytest.mark.slow
def test_sigkill_mid_sweep_then_resume_gives_every_run_exactly_once(tmp_path: Path) -> None:
    schema = write_schema(tmp_path, MINI.replace("repetitions: 2", "repetitions: 3"))
    db = tmp_path / "killed.duckdb"
    proc = subprocess.Popen(
        [*MRCOMM, "sweep", str(schema), "--jobs", "2", "--db", str(db)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        cwd=ROOT,
        start_new_session=True,  # its own process group: the workers die with it
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert proc.stdout is not None
    lines = []
    try:
        for line in proc.stdout:  # one line per stored run (not a terminal)
            lines.append(line)
            if line.startswith("[3/12]"):
                break
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL and len(lines) == 3, lines
    stored = inspect_database(db).runs
    assert 3 <= len(stored) < 12 and set(stored.values()) == {"ok"}

    resumed = mrcomm("sweep", schema, "--jobs", "2", "--db", db)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{12 - len(stored)} new ok, 0 failed, {len(stored)} already done" in resumed.stdout

    # The same sweep, never interrupted, stores exactly the same rows.
    reference = tmp_path / "reference.duckdb"
    with ThreadPoolExecutor(2) as pool:
        execute_sweep(plan_sweep(load_experiment(schema), reference), pool, max_in_flight=2)
    got, want = snapshot(db), snapshot(reference)
    assert len(got["runs"]) == 12 and len({r[0] for r in got["runs"]}) == 12
    assert got == want
