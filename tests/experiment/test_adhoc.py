"""Ad-hoc runs (``mrcomm run|live|collect --db``): one finished run stored next to
sweeps — repetitions numbered per configuration, ids that differ by mode and options,
bad databases refused untouched, one transaction, and sweeps in the same database
still resume."""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import duckdb
import pytest
import yaml

import mrcomm.experiment.store as store_module
from mrcomm.errors import InputError
from mrcomm.experiment.adhoc import ADHOC_SOURCE, check_target, command_line, store_result
from mrcomm.experiment.api import load_results
from mrcomm.experiment.runner import execute_sweep, plan_sweep
from mrcomm.experiment.schema import load_experiment
from mrcomm.experiment.store import inspect_database
from mrcomm.run.config import make_config
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import run_mission
from tests.conftest import S1_PATH
from tests.experiment.helpers import MINI, fake_ok, snapshot, write_schema


@pytest.fixture(scope="module")
def sim(s1_resources: Any) -> MissionResult:
    """A short real LF mission (every table gets rows)."""
    config = make_config(
        None, scenario=S1_PATH, network="ah", threshold="slt", behaviour="lf", seed=7, max_time=20
    )
    return run_mission(config, s1_resources)


def as_live(result: MissionResult, **extra: Any) -> MissionResult:
    """The same result as ``mrcomm collect`` labels a live run."""
    return dataclasses.replace(result, config={**result.config, "mode": "live", **extra})


def runs(db: Path) -> list[dict[str, Any]]:
    con = duckdb.connect(str(db), read_only=True)
    try:
        cur = con.execute(
            "SELECT run_id, config_id, experiment, label, repetition, seed, mode, status "
            "FROM runs ORDER BY run_id"
        )
        names = [d[0] for d in cur.description]
        return [dict(zip(names, row, strict=True)) for row in cur.fetchall()]
    finally:
        con.close()


def test_the_same_run_is_stored_once_unless_a_duplicate_is_asked_for(
    tmp_path: Path, sim: MissionResult
) -> None:
    db = tmp_path / "r.duckdb"
    first = store_result(db, sim)
    again = store_result(db, sim)
    # Same configuration, seed and inputs: the same result, already stored.
    assert not again.new and again.run_id == first.run_id and again.repetition == 1
    assert "already stored as" in again.describe()
    assert len(runs(db)) == 1
    second = store_result(db, sim, keep_duplicate=True)
    assert second.new and (first.repetition, second.repetition) == (1, 2)
    assert first.config_id == second.config_id and first.config_id.startswith("AH_LF_SPL0_SLT-")
    assert second.run_id == f"{first.config_id}-r002"
    rows = runs(db)
    assert [r["repetition"] for r in rows] == [1, 2]
    assert all(
        r["seed"] == 7 and r["mode"] == "sim" and r["experiment"] == "adhoc" and r["status"] == "ok"
        for r in rows
    )
    info = inspect_database(db)
    assert info.experiments == {"adhoc": 0} and info.sources == {"adhoc": ADHOC_SOURCE}
    # Every table is filled, as for a swept run.
    tables = snapshot(db)
    for table in ("robot_metrics", "messages", "links", "intervals", "events"):
        assert {row[0] for row in tables[table]} == {first.run_id, second.run_id}, table
    # The experiment's YAML lists both runs with what reproduces them.
    con = duckdb.connect(str(db), read_only=True)
    text = con.execute("SELECT schema_yaml FROM experiments").fetchone()[0]
    options = con.execute("SELECT options FROM configs").fetchone()[0]
    con.close()
    listed = yaml.safe_load(text)["runs"]
    assert [e["run_id"] for e in listed] == [first.run_id, second.run_id]
    assert listed[0]["command"] == (
        f"mrcomm run {S1_PATH.resolve()} --network ah --threshold slt --behaviour lf "
        "--max-time 20 --seed 7"
    )
    assert '"max_time": 20.0' in options and '"scenario": "/' in options  # absolute path


def test_a_live_run_is_stored_once_per_record(tmp_path: Path, sim: MissionResult) -> None:
    db = tmp_path / "r.duckdb"
    first = store_result(db, as_live(sim), run_fingerprint="record-a")
    same_record = store_result(db, as_live(sim), run_fingerprint="record-a")
    other_record = store_result(db, as_live(sim), run_fingerprint="record-b")
    assert not same_record.new and same_record.run_id == first.run_id
    assert other_record.new and other_record.repetition == 2  # another live run, same seed
    with pytest.raises(ValueError, match="fingerprint of its record"):
        store_result(db, as_live(sim))


def test_ids_differ_by_mode_options_and_experiment(tmp_path: Path, sim: MissionResult) -> None:
    db = tmp_path / "r.duckdb"
    records = iter(f"record-{i}" for i in range(100))
    store_live = functools.partial(_store_live, records)
    sim_run = store_result(db, sim)
    live = store_live(db, as_live(sim, speed=10.0))
    assert live.config_id != sim_run.config_id and live.mode == "live"
    assert live.config_id.startswith("AH_LF_SPL0_SLT_LIVE-") and live.repetition == 1
    # Another speed or a lease is another configuration ...
    faster = store_live(db, as_live(sim, speed=20.0))
    leased = store_live(db, as_live(sim, speed=10.0), live_options={"lease": 30.0})
    assert len({live.config_id, faster.config_id, leased.config_id}) == 3
    # ... while options at their default are not part of the id: `collect` (which sees
    # the record's speed only) and `live` (which gives every option) agree.
    again = store_live(
        db,
        as_live(sim, speed=10.0),
        live_options={"speed": 10.0, "protocol": "tcp", "insecure": False},
    )
    assert again.config_id == live.config_id and again.repetition == 2
    other = store_result(db, sim, experiment="bench")
    assert other.config_id != sim_run.config_id and other.repetition == 1
    modes = {r["run_id"]: r["mode"] for r in runs(db)}
    assert modes[live.run_id] == "live" and modes[sim_run.run_id] == "sim"
    # The notebook API keeps returning every run, or one mode on request.
    res = load_results(db)
    assert sorted(res.runs["mode"].unique()) == ["live", "sim"] and len(res.runs) == 6
    res.close()
    res = load_results(db, mode="live")
    assert set(res.runs["mode"]) == {"live"} and len(res.runs) == 4
    assert set(res.configs["config_id"]) == {live.config_id, faster.config_id, leased.config_id}
    assert set(res.intervals["run_id"]) == set(res.runs["run_id"])
    res.close()
    res = load_results(db, experiment="bench", mode="sim")
    assert res.runs["run_id"].tolist() == [other.run_id]
    assert res.configs["config_id"].tolist() == [other.config_id]
    res.close()


def _store_live(records: Any, db: Path, result: MissionResult, **kwargs: Any) -> Any:
    return store_result(db, result, run_fingerprint=next(records), **kwargs)


def test_paths_are_absolute_so_the_working_directory_does_not_matter(
    tmp_path: Path, sim: MissionResult, monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "r.duckdb"
    monkeypatch.chdir(S1_PATH.parent)
    relative = dataclasses.replace(sim, config={**sim.config, "scenario": S1_PATH.name})
    assert store_result(db, relative).config_id == store_result(db, sim).config_id


def test_command_line_of_a_live_run() -> None:
    options = {"scenario": "/s.yaml", "spl": 25.0, "speed": 10.0, "team_dir": "/c"}
    assert command_line("live", options, 3) == (
        "mrcomm live /s.yaml --spl 25 --speed 10 --team-dir /c --seed 3"
    )
    insecure = {"scenario": "/s.yaml", "insecure": True}
    assert command_line("live", insecure, 3) == "mrcomm live /s.yaml --insecure --seed 3"


def _fingerprint(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_bad_databases_and_names_are_refused_untouched(tmp_path: Path, sim: MissionResult) -> None:
    text = tmp_path / "notes.duckdb"
    text.write_text("not a database\n")
    with pytest.raises(InputError, match="damaged or not a DuckDB database"):
        check_target(text)
    with pytest.raises(InputError, match="damaged or not a DuckDB database"):
        store_result(text, sim)
    assert text.read_text() == "not a database\n"
    with pytest.raises(InputError, match="--experiment: 'a b' is not a valid name"):
        check_target(tmp_path / "new.duckdb", "a b")
    assert not (tmp_path / "new.duckdb").exists()
    # An experiment that is a sweep's is not for ad-hoc runs (its resume would break).
    db = tmp_path / "r.duckdb"
    exp = load_experiment(write_schema(tmp_path))
    with ThreadPoolExecutor(2) as pool:
        execute_sweep(plan_sweep(exp, db), pool, max_in_flight=4, run_fn=fake_ok)
    before = _fingerprint(db)
    with pytest.raises(InputError, match="experiment 'mini' in this database is a sweep"):
        store_result(db, sim, experiment="mini")
    assert _fingerprint(db) == before


def test_a_failed_write_leaves_no_trace(
    tmp_path: Path, sim: MissionResult, monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "r.duckdb"
    store_result(db, sim)
    before = snapshot(db)
    real = store_module._frame

    def fail_on_events(table: str, rows: list[tuple[Any, ...]]) -> Any:
        if table == "events":
            raise RuntimeError("disk full")
        return real(table, rows)

    monkeypatch.setattr(store_module, "_frame", fail_on_events)
    with pytest.raises(RuntimeError, match="disk full"):
        store_result(db, as_live(sim, speed=10.0), experiment="other", run_fingerprint="r")
    monkeypatch.undo()
    assert snapshot(db) == before
    info = inspect_database(db)
    assert set(info.experiments) == {"adhoc"} and len(info.configs) == 1  # no half-registration


def test_a_sweep_into_the_same_database_still_resumes(tmp_path: Path, sim: MissionResult) -> None:
    db = tmp_path / "r.duckdb"
    store_result(db, sim)
    exp = load_experiment(write_schema(tmp_path))
    plan = plan_sweep(exp, db)
    assert len(plan.todo) == 8
    with ThreadPoolExecutor(2) as pool:  # interrupted: only half of the runs
        execute_sweep(
            dataclasses.replace(plan, todo=plan.todo[:4]), pool, max_in_flight=2, run_fn=fake_ok
        )
    stored = store_result(
        db, as_live(sim, speed=10.0), run_fingerprint="r"
    )  # an ad-hoc run in between
    resumed = plan_sweep(exp, db)
    assert [s.run_id for s in resumed.todo] == [s.run_id for s in plan.todo[4:]]
    with ThreadPoolExecutor(2) as pool:
        report = execute_sweep(resumed, pool, max_in_flight=2, run_fn=fake_ok)
    assert (report.ok, report.skipped) == (4, 4)
    assert plan_sweep(exp, db).todo == ()
    info = inspect_database(db)
    assert info.experiments == {"adhoc": 0, "mini": 5}
    assert sum(1 for r in runs(db) if r["experiment"] == "mini") == 8
    assert stored.run_id in info.runs
    # The sweep stays the database's latest experiment (meta), ad-hoc runs do not touch it.
    con = duckdb.connect(str(db), read_only=True)
    assert con.execute("SELECT value FROM meta WHERE key = 'experiment'").fetchone() == ("mini",)
    con.close()
    # A schema named like an ad-hoc experiment is refused: the two would mix.
    clash = load_experiment(write_schema(tmp_path, MINI.replace("name: mini", "name: adhoc")))
    with pytest.raises(InputError, match="experiment 'adhoc' in this database holds ad-hoc"):
        plan_sweep(clash, db)
