"""The results database: round trip of a real run, refusal of foreign databases without
touching them, replacement of failed runs, and a SIGKILL in the middle of a write."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import duckdb
import pytest

from mrcomm.errors import InputError
from mrcomm.experiment.api import load_results
from mrcomm.experiment.rows import failure_rows, result_rows
from mrcomm.experiment.runner import plan_sweep
from mrcomm.experiment.schema import load_experiment
from mrcomm.experiment.store import ResultStore, inspect_database
from mrcomm.experiment.tables import RUN_TABLES, TABLES, column_names
from mrcomm.sim.mission import run_mission
from tests.experiment.helpers import write_schema


def _fingerprint(path: Path) -> tuple[str, float]:
    return hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime


def test_a_run_round_trips_into_every_table(tmp_path: Path, s1_resources) -> None:  # type: ignore[no-untyped-def]
    exp = load_experiment(write_schema(tmp_path))
    spec = next(s for s in exp.runs() if s.config.behaviour == "lf")
    result = run_mission(spec.config, s1_resources)
    rows = result_rows(spec, result, 0.5)
    db = tmp_path / "r.duckdb"
    store = ResultStore.open(db)
    store.register(exp)
    store.write_run(rows)
    store.close()
    con = duckdb.connect(str(db), read_only=True)
    for table in TABLES:  # the contract's columns, in order
        cols = [r[0] for r in con.execute(f"DESCRIBE {table}").fetchall()]
        assert tuple(cols) == column_names(table), table
    run = dict(zip(column_names("runs"), con.execute("SELECT * FROM runs").fetchone(), strict=True))
    m = result.mission
    assert run["run_id"] == spec.run_id and run["status"] == "ok" and run["seed"] == spec.seed
    assert run["label"] == "WLAN_LF_SPL0_SLT" and run["scenario"] == "S1" and run["mode"] == "sim"
    assert run["total_distance"] == pytest.approx(m["total_distance"])
    assert run["n_failed_tasks"] == len(m["failed_tasks"])
    assert run["leader_movement_time"] == pytest.approx(m["leader_movement_time"])
    assert run["aon_publications"] == result.aon["total"]["publications"]
    assert run["finished_at"] is not None and run["wall_time_s"] == 0.5
    counts = {t: con.execute(f"SELECT count(*) FROM {t}").fetchone()[0] for t in RUN_TABLES}
    assert counts["robot_metrics"] > 3 * 20
    assert counts["failed_tasks"] == len(m["failed_tasks"])
    assert counts["messages"] == sum(len(t) for t in result.messages_by_agent.values())
    assert counts["links"] == len(result.links) and counts["intervals"] > 0
    assert counts["events"] > 0 and counts["rssi"] == 0  # SLT has no RSSI
    dist = con.execute(
        "SELECT value FROM robot_metrics WHERE robot = 'robot_1' AND metric = 'distance'"
    ).fetchone()[0]
    assert dist == pytest.approx(result.robots["robot_1"]["distance"])
    data = con.execute("SELECT data FROM events WHERE label = 'role_assigned' LIMIT 1").fetchone()
    assert "leader" in json.loads(data[0])
    configs = con.execute("SELECT count(*), count(DISTINCT label) FROM configs").fetchone()
    assert configs == (4, 4)
    con.close()


def test_a_failed_run_is_replaced_by_its_rerun(tmp_path: Path) -> None:
    exp = load_experiment(write_schema(tmp_path))
    spec = exp.runs()[0]
    db = tmp_path / "r.duckdb"
    store = ResultStore.open(db)
    store.register(exp)
    store.write_run(failure_rows(spec, "error", "RuntimeError: boom", 1.0))
    store.close()
    plan = plan_sweep(exp, db)
    assert spec.run_id in plan.replace and len(plan.todo) == 8
    store = ResultStore.open(db)
    store.write_run(failure_rows(spec, "ok", "", 2.0), replace=True)
    store.close()
    assert inspect_database(db).runs == {spec.run_id: "ok"}
    assert len(plan_sweep(exp, db).todo) == 7


def test_other_schema_versions_are_refused_untouched(tmp_path: Path) -> None:
    exp = load_experiment(write_schema(tmp_path))
    db = tmp_path / "old.duckdb"
    con = duckdb.connect(str(db))
    con.execute("CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT)")
    con.execute("INSERT INTO meta VALUES ('schema_version', '0')")
    con.close()
    before = _fingerprint(db)
    with pytest.raises(InputError, match="results schema version '0'"):
        plan_sweep(exp, db)
    assert _fingerprint(db) == before and not Path(f"{db}.wal").exists()


def test_a_version_6_database_is_read_as_it_is_and_upgraded_when_written(
    tmp_path: Path, s1_resources
) -> None:  # type: ignore[no-untyped-def]
    """Version 7 only added the shared channel's two message columns: a version 6 file
    reads (the columns missing), and a writer adds them in place, keeping every row."""
    from mrcomm.experiment.store import open_readonly

    exp = load_experiment(write_schema(tmp_path))
    db = tmp_path / "v6.duckdb"
    spec = next(iter(exp.runs()))
    store = ResultStore.open(db)
    store.register(exp)
    store.write_run(result_rows(spec, run_mission(spec.config, s1_resources), 1.0))
    store.close()
    con = duckdb.connect(str(db))
    con.execute("ALTER TABLE messages DROP COLUMN airtime_s")
    con.execute("ALTER TABLE messages DROP COLUMN dropped_collision")
    con.execute("UPDATE meta SET value = '6' WHERE key = 'schema_version'")
    rows = con.execute("SELECT count(*) FROM messages").fetchone()
    con.close()
    before = _fingerprint(db)
    reader = open_readonly(db)
    assert reader.execute("SELECT count(*) FROM messages").fetchone() == rows
    reader.close()
    assert _fingerprint(db) == before  # reading changed nothing
    ResultStore.open(db).close()
    con = duckdb.connect(str(db), read_only=True)
    version = con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
    assert version == ("7",)
    described = [r[0] for r in con.execute("DESCRIBE messages").fetchall()]
    assert tuple(described) == column_names("messages")
    assert con.execute("SELECT count(*) FROM messages").fetchone() == rows
    con.close()


def test_a_database_with_other_columns_is_refused_untouched(tmp_path: Path) -> None:
    exp = load_experiment(write_schema(tmp_path))
    db = tmp_path / "dev.duckdb"
    ResultStore.open(db).close()
    con = duckdb.connect(str(db))
    con.execute("ALTER TABLE runs DROP COLUMN near_collisions_missed")
    con.close()
    before = _fingerprint(db)
    with pytest.raises(InputError, match="table 'runs' has other columns"):
        plan_sweep(exp, db)
    assert _fingerprint(db) == before


def test_foreign_files_are_refused(tmp_path: Path) -> None:
    text = tmp_path / "notes.duckdb"
    text.write_text("not a database\n" * 100)
    with pytest.raises(InputError, match="damaged or not a DuckDB database"):
        inspect_database(text)
    assert text.read_text() == "not a database\n" * 100
    other = tmp_path / "other.duckdb"
    con = duckdb.connect(str(other))
    con.execute("CREATE TABLE t(x INT)")
    con.close()
    with pytest.raises(InputError, match="not an MRComm results database"):
        inspect_database(other)


@pytest.mark.parametrize("keep", [100, 12288, 0.5])
def test_a_truncated_database_is_reported_as_damaged(tmp_path: Path, keep: float) -> None:
    """Cut short (a disk full, a copy interrupted): damaged, never "in use", never a
    traceback — whether DuckDB fails on opening it or only on reading a table."""
    db = tmp_path / "r.duckdb"
    store = ResultStore.open(db)
    store.close()
    con = duckdb.connect(str(db))
    con.execute("CREATE TABLE filler AS SELECT range AS x FROM range(200000)")
    con.close()
    size = db.stat().st_size
    with db.open("r+b") as f:
        f.truncate(int(size * keep) if keep < 1 else int(keep))
    with pytest.raises(InputError, match="damaged or not a DuckDB database") as err:
        inspect_database(db)
        load_results(db)
    assert "in use" not in str(err.value)


def test_a_database_in_use_is_reported(tmp_path: Path) -> None:
    db = tmp_path / "r.duckdb"
    ResultStore.open(db).close()
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            f"import duckdb, sys; c = duckdb.connect({str(db)!r}); print('held', flush=True);"
            " sys.stdin.read()",
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        with pytest.raises(InputError, match="in use by another process"):
            inspect_database(db)
    finally:
        holder.communicate("", timeout=60)


KILLER = """
import os, signal, sys
from pathlib import Path
import mrcomm.experiment.store as store_module
from mrcomm.experiment.rows import result_rows
from mrcomm.experiment.schema import load_experiment
from mrcomm.experiment.store import ResultStore
from mrcomm.sim.mission import run_mission

exp = load_experiment(sys.argv[1])
runs = exp.runs()
result = run_mission(runs[1].config.model_copy(update={"max_time": 10.0}))
store = ResultStore.open(Path(sys.argv[2]))
store.register(exp)
for spec in runs[:2]:
    store.write_run(result_rows(spec, result, 0.1))
frame = store_module._frame

def frame_then_die(table, rows):
    # The runs row and robot metrics of the third run are already inserted when the
    # process dies, inside the run's transaction.
    if table == "messages":
        os.kill(os.getpid(), signal.SIGKILL)
    return frame(table, rows)

store_module._frame = frame_then_die
store.write_run(result_rows(runs[2], result, 0.1))
"""


def test_sigkill_in_the_middle_of_a_write_leaves_whole_runs(tmp_path: Path) -> None:
    schema = write_schema(tmp_path)
    db = tmp_path / "r.duckdb"
    proc = subprocess.run(
        [sys.executable, "-c", KILLER, str(schema), str(db)], capture_output=True, text=True
    )
    assert proc.returncode == -9, proc.stderr
    exp = load_experiment(schema)
    runs = exp.runs()
    info = inspect_database(db)
    assert info.runs == {runs[0].run_id: "ok", runs[1].run_id: "ok"}
    con = duckdb.connect(str(db), read_only=True)
    for table in RUN_TABLES:
        ids = {r[0] for r in con.execute(f"SELECT DISTINCT run_id FROM {table}").fetchall()}
        assert ids <= set(info.runs), table  # nothing of the killed run
    per_run = con.execute(
        "SELECT run_id, count(*) FROM robot_metrics GROUP BY run_id ORDER BY run_id"
    ).fetchall()
    assert len(per_run) == 2 and per_run[0][1] == per_run[1][1]
    con.close()
    plan = plan_sweep(exp, db)
    assert [s.run_id for s in plan.todo] == [s.run_id for s in runs[2:]]


def test_no_progress_bar_on_any_connection(tmp_path: Path) -> None:
    """DuckDB draws a progress bar on stdout for queries over 2 s: into the CSV or JSON
    a command prints. Every connection of the store turns it off."""
    from mrcomm.experiment import store

    con = store._connect(tmp_path / "x.duckdb", read_only=False)
    try:
        (value,) = con.execute("SELECT current_setting('enable_progress_bar')").fetchone()
    finally:
        con.close()
    assert value is False
