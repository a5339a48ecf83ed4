"""Fixtures of the analysis tests: a small real study swept into a results database
with ``mrcomm sweep`` (S1 · AH · SLT · {NB, LF} · SPL {0, 50} · 2 repetitions), built
once per test session."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import ROOT, S1_PATH

MRCOMM = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]

SCHEMA = f"""\
name: small
description: S1 x AH x SLT x {{NB, LF}} x SPL{{0,50}} (analysis tests).
scenario: {S1_PATH}
repetitions: 2
base_seed: 11
factors:
  network: [ah]
  spl: [0, 50]
  threshold: [slt]
  behaviour: [nb, lf]
"""


def mrcomm(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*MRCOMM, *args], capture_output=True, text=True, cwd=cwd or ROOT, timeout=300
    )


def make_study_db(directory: Path) -> Path:
    schema = directory / "small.yaml"
    schema.write_text(SCHEMA)
    db = directory / "small.duckdb"
    proc = mrcomm("sweep", str(schema), "--db", str(db), "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    return db


@pytest.fixture(scope="session")
def study_db(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_study_db(tmp_path_factory.mktemp("study"))


@pytest.fixture(scope="session")
def study(study_db: Path) -> Any:
    from mrcomm.experiment.api import load_results

    return load_results(study_db)


@pytest.fixture(scope="session")
def built(study: Any, study_db: Path, tmp_path_factory: pytest.TempPathFactory) -> Any:
    """The full report of the small study (every figure, PNG and SVG)."""
    from mrcomm.analysis.report import build_report

    return build_report(study, tmp_path_factory.mktemp("report") / "out", db_path=study_db)
