"""The sweep runner: crashes, dead workers and timeouts are recorded and the sweep goes
on; failed runs are re-run; a database of another definition is refused."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from mrcomm.errors import InputError
from mrcomm.experiment.runner import execute_sweep, plan_sweep, process_pool
from mrcomm.experiment.schema import load_experiment
from mrcomm.experiment.store import inspect_database
from mrcomm.experiment.worker import RunTask, RunTimeout, _alarm, run_one
from tests.experiment.helpers import (
    MINI,
    crash_on_r002,
    die_on_first_config_r002,
    fake_ok,
    snapshot,
    write_schema,
)


def test_a_crashing_run_is_recorded_and_rerun_next_time(tmp_path: Path) -> None:
    exp = load_experiment(write_schema(tmp_path))
    db = tmp_path / "r.duckdb"
    seen: list[str] = []
    with ThreadPoolExecutor(2) as pool:
        report = execute_sweep(
            plan_sweep(exp, db),
            pool,
            max_in_flight=4,
            run_fn=crash_on_r002,
            on_outcome=lambda o: seen.append(o.status),
        )
    assert (report.ok, report.failed, report.total, report.skipped) == (4, 4, 8, 0)
    assert sorted(seen) == ["error"] * 4 + ["ok"] * 4
    assert all(msg == "RuntimeError: boom" for _, _, msg in report.failures)
    assert sorted(inspect_database(db).runs.values()) == ["error"] * 4 + ["ok"] * 4
    plan = plan_sweep(exp, db)
    assert len(plan.todo) == 4 and all(s.repetition == 2 for s in plan.todo)
    with ThreadPoolExecutor(2) as pool:
        again = execute_sweep(plan, pool, max_in_flight=4, run_fn=fake_ok)
    assert (again.ok, again.failed, again.skipped) == (4, 0, 4)
    assert set(inspect_database(db).runs.values()) == {"ok"}
    assert len(snapshot(db)["runs"]) == 8


def test_a_dead_worker_process_costs_only_its_run(tmp_path: Path) -> None:
    exp = load_experiment(write_schema(tmp_path))
    db = tmp_path / "r.duckdb"
    pools = [process_pool(2)]

    def respawn():  # type: ignore[no-untyped-def]
        pools.append(process_pool(2))
        return pools[-1]

    try:
        report = execute_sweep(
            plan_sweep(exp, db),
            pools[0],
            max_in_flight=2,
            run_fn=die_on_first_config_r002,
            respawn=respawn,
        )
    finally:
        for pool in pools:
            pool.shutdown(cancel_futures=True)
    assert report.failed >= 1 and report.ok + report.failed == 8 and report.not_run == 0
    runs = inspect_database(db).runs
    assert len(runs) == 8
    killer = next(s.run_id for s in exp.runs() if s.repetition == 2 and s.config.spl == 0)
    assert runs[killer] == "error"
    assert any("worker process died" in m for _, _, m in report.failures)


def test_run_one_reports_timeouts_and_errors_instead_of_raising(tmp_path: Path) -> None:
    spec = load_experiment(write_schema(tmp_path)).runs()[0]
    late = run_one(RunTask(spec, timeout_s=1e-6))
    assert late.status == "timeout" and "wall-clock limit" in late.message
    assert late.rows["runs"][0][12] == "timeout" and set(late.rows) == {"runs"}
    missing = spec.config.model_copy(update={"scenario": tmp_path / "nowhere.yaml"})
    broken = run_one(RunTask(type(spec)(**{**spec.__dict__, "config": missing})))
    assert broken.status == "error" and broken.message.startswith("InputError:")
    assert "Traceback" in (broken.error or "")


def test_a_changed_definition_or_seed_is_refused(tmp_path: Path) -> None:
    db = tmp_path / "r.duckdb"
    exp = load_experiment(write_schema(tmp_path))
    with ThreadPoolExecutor(1) as pool:
        execute_sweep(plan_sweep(exp, db, repetitions=1), pool, max_in_flight=1, run_fn=fake_ok)
    changed = load_experiment(write_schema(tmp_path, MINI.replace("max_time: 30", "max_time: 40")))
    with pytest.raises(InputError, match="different configuration WLAN_NB_SPL0_SLT"):
        plan_sweep(changed, db)
    reseeded = load_experiment(write_schema(tmp_path, MINI.replace("base_seed: 5", "base_seed: 6")))
    with pytest.raises(InputError, match="base_seed 5"):
        plan_sweep(reseeded, db)
    with pytest.raises(InputError, match="--reps"):
        plan_sweep(exp, db, repetitions=0)
    # More repetitions later: only the new ones are left to do.
    assert len(plan_sweep(exp, db, repetitions=3).todo) == 8


def test_recording_directory_names_one_file_per_run(tmp_path: Path) -> None:
    exp = load_experiment(write_schema(tmp_path, MINI.replace("max_time: 30", "max_time: 5")))
    db, rec = tmp_path / "r.duckdb", tmp_path / "rec"
    rec.mkdir()
    with ThreadPoolExecutor(1) as pool:
        execute_sweep(plan_sweep(exp, db, repetitions=1), pool, max_in_flight=1, record_dir=rec)
    names = sorted(p.name for p in rec.iterdir())
    plain = tmp_path / "plain.duckdb"  # recording only observes: same rows without it
    with ThreadPoolExecutor(1) as pool:
        execute_sweep(plan_sweep(exp, plain, repetitions=1), pool, max_in_flight=1)
    assert snapshot(plain) == snapshot(db)
    assert names == sorted(f"{s.run_id}.mcap" for s in exp.runs(1))
    assert plan_sweep(exp, db, repetitions=1, record_dir=rec).todo == ()
    (rec / names[0]).unlink()  # a lost recording is made again
    assert len(plan_sweep(exp, db, repetitions=1, record_dir=rec).todo) == 1


def test_the_alarm_stops_a_recorded_run_at_its_deadline() -> None:
    # Recordings step the mission themselves; in a worker's main thread a timer cuts
    # them off (in this test: pytest's main thread).
    started = time.perf_counter()
    with pytest.raises(RunTimeout), _alarm(started + 0.05):
        while time.perf_counter() - started < 5.0:
            pass
    assert time.perf_counter() - started < 1.0
    with _alarm(None):  # no deadline: nothing happens
        pass
