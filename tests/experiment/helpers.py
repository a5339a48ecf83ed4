"""Shared helpers of the sweep tests: small schemas, fake run functions (module level,
so that worker processes can import them) and a database snapshot for comparisons."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import duckdb

from mrcomm.experiment.rows import failure_rows
from mrcomm.experiment.tables import RUN_TABLES
from mrcomm.experiment.worker import RunOutcome, RunTask
from tests.conftest import S1_PATH

#: 4 configurations of short (30 s simulated) missions: fast, yet every table is filled.
MINI = f"""\
name: mini
scenario: {S1_PATH}
repetitions: 2
base_seed: 5
factors:
  network: [wlan]
  spl: [0, 50]
  behaviour: [nb, lf]
  threshold: slt
options: {{max_time: 30}}
"""


def write_schema(directory: Path, text: str = MINI, name: str = "mini.yaml") -> Path:
    path = directory / name
    path.write_text(text, encoding="utf-8")
    return path


def fake_ok(task: RunTask) -> RunOutcome:
    """A run that 'succeeds' at once with only a runs row (no simulation)."""
    rows = failure_rows(task.spec, "ok", "", 0.0)
    return RunOutcome(task.spec.run_id, "ok", None, 0.0, rows)


def crash_on_r002(task: RunTask) -> RunOutcome:
    """Raises inside the run for every repetition 2."""
    if task.spec.repetition == 2:
        raise RuntimeError("boom")
    return fake_ok(task)


def die_on_first_config_r002(task: RunTask) -> RunOutcome:
    """Kills its worker process (as a segfault would) for one particular run."""
    if (
        task.spec.repetition == 2
        and task.spec.config.spl == 0
        and task.spec.config.behaviour == "nb"
    ):
        os._exit(3)
    return fake_ok(task)


def snapshot(db: Path) -> dict[str, list[tuple[Any, ...]]]:
    """Every per-run table, sorted, without wall-clock columns (which always differ)."""
    con = duckdb.connect(str(db), read_only=True)
    try:
        out: dict[str, list[tuple[Any, ...]]] = {}
        for table in RUN_TABLES:
            cols = [
                r[0]
                for r in con.execute(
                    "SELECT column_name FROM duckdb_columns() WHERE table_name = ?", [table]
                ).fetchall()
                if r[0] not in ("wall_time_s", "finished_at")
            ]
            rows = con.execute(f"SELECT {', '.join(cols)} FROM {table}").fetchall()
            out[table] = sorted(rows, key=repr)
        return out
    finally:
        con.close()
