"""Notebook API (one call -> DataFrames) and export to CSV / Parquet."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import duckdb
import pytest

from mrcomm.errors import InputError
from mrcomm.experiment.api import load_results
from mrcomm.experiment.export import export_tables
from mrcomm.experiment.runner import execute_sweep, plan_sweep
from mrcomm.experiment.schema import load_experiment
from mrcomm.experiment.tables import RUN_TABLES, TABLES, column_names
from tests.experiment.helpers import MINI, write_schema


@pytest.fixture(scope="module")
def swept(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A database with the 4 configurations of MINI, one 20 s run each."""
    tmp = tmp_path_factory.mktemp("swept")
    exp = load_experiment(write_schema(tmp, MINI.replace("max_time: 30", "max_time: 20")))
    db = tmp / "results.duckdb"
    with ThreadPoolExecutor(2) as pool:
        execute_sweep(plan_sweep(exp, db, repetitions=1), pool, max_in_flight=2)
    return db


def test_load_results_gives_every_table_as_a_dataframe(swept: Path) -> None:
    res = load_results(swept)
    try:
        for table in ("configs", *RUN_TABLES):
            frame = getattr(res, table)
            assert tuple(frame.columns) == column_names(table), table
        assert len(res.runs) == 4 and len(res.ok_runs) == 4 and len(res.configs) == 4
        assert list(res.runs.label) == sorted(res.runs.label)
        assert res.runs.loc[res.runs.behaviour == "nb", "leader_movement_time"].isna().all()
        assert res.runs.loc[res.runs.behaviour == "lf", "leader_movement_time"].notna().all()
        per_robot = res.robot_metrics.pivot_table(
            index=["run_id", "robot"], columns="metric", values="value"
        )
        assert per_robot.shape[0] == 12 and "distance" in per_robot.columns
        assert set(res.messages.topic) >= {"pose", "task_status"}
        assert res.con.execute("SELECT count(*) FROM runs").fetchone() == (4,)
        only = load_results(swept, experiment="mini")
        assert len(only.runs) == 4 and len(only.intervals) == len(res.intervals)
        none = load_results(swept, experiment="other")
        assert none.runs.empty and none.intervals.empty
        only.close()
        none.close()
    finally:
        res.close()


def test_load_results_refuses_a_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="database not found"):
        load_results(tmp_path / "nope.duckdb")


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_export_writes_one_file_per_table(swept: Path, tmp_path: Path, fmt: str) -> None:
    out = tmp_path / "out"
    written = export_tables(swept, fmt, out)
    assert sorted(p.name for p in written) == sorted(f"{t}.{fmt}" for t in TABLES)
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in written)
    con = duckdb.connect()
    runs = con.sql(f"SELECT * FROM '{out / ('runs.' + fmt)}'").df()
    assert len(runs) == 4 and tuple(runs.columns) == column_names("runs")
    n = con.execute(f"SELECT count(*) FROM '{out / ('intervals.' + fmt)}'").fetchone()
    src = duckdb.connect(str(swept), read_only=True)
    assert n == src.execute("SELECT count(*) FROM intervals").fetchone()
    src.close()


def test_export_rejects_an_unknown_format(swept: Path, tmp_path: Path) -> None:
    with pytest.raises(InputError, match="did you mean 'parquet'"):
        export_tables(swept, "parket", tmp_path / "out")
    assert not (tmp_path / "out").exists()
