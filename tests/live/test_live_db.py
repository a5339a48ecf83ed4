"""Live runs in the results database (issue 7: ``mrcomm live`` "stores the run with
mode=live wherever sweeps store results"): one short real live mission stored by
``mrcomm live --db``, its record stored again by ``mrcomm collect --db``, next to a
simulated run of the same options; and a bad ``--db`` refused before any process."""

from __future__ import annotations

import json
from pathlib import Path

import duckdb
import pytest

from .helpers import S1
from .test_live_cli import mrcomm, one_line_error
from .test_live_netns import short_scenario

pytestmark = pytest.mark.slow


def test_live_and_collect_store_the_run_with_mode_live(tmp_path: Path) -> None:
    scenario = short_scenario(tmp_path)
    db = tmp_path / "r.duckdb"
    records = tmp_path / "records"
    options = ["--max-time", "300", "--seed", "4"]
    done = mrcomm(
        "live", str(scenario), *options, "--speed", "10", "--json", "--record-dir", str(records),
        "--db", str(db), timeout=180,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    live = json.loads(done.stdout)
    stored = live["stored"]
    assert stored["mode"] == "live" and stored["repetition"] == 1
    assert stored["config_id"].startswith("WLAN_NB_SPL0_LIVE-")
    # The same record collected again: the same run (its speed is in the record), which
    # is stored already; kept as a duplicate only on request (the next repetition).
    done = mrcomm("collect", str(records), "--db", str(db), "--json", timeout=60)
    assert done.returncode == 0, done.stderr[-2000:]
    same = json.loads(done.stdout)["stored"]
    assert same["run_id"] == stored["run_id"] and same["new"] is False
    done = mrcomm(
        "collect", str(records), "--db", str(db), "--json", "--keep-duplicate", timeout=60
    )
    assert done.returncode == 0, done.stderr[-2000:]
    again = json.loads(done.stdout)["stored"]
    assert again["config_id"] == stored["config_id"] and again["repetition"] == 2
    # The same options simulated: another configuration, mode sim.
    done = mrcomm("run", str(scenario), *options, "--db", str(db), "--json", timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    sim = json.loads(done.stdout)["stored"]
    assert sim["mode"] == "sim" and sim["config_id"] != stored["config_id"]
    con = duckdb.connect(str(db), read_only=True)
    rows = con.execute(
        "SELECT run_id, mode, label, seed, status, total_distance, tasks_completed "
        "FROM runs ORDER BY mode, repetition"
    ).fetchall()
    options_row = con.execute(
        "SELECT options FROM configs WHERE config_id = ?", [stored["config_id"]]
    ).fetchone()
    counts_row = con.execute(
        "SELECT count(*) FROM intervals WHERE run_id = ?", [stored["run_id"]]
    ).fetchone()
    assert options_row is not None and counts_row is not None
    options_json, counts = options_row[0], counts_row[0]
    con.close()
    assert [r[:5] for r in rows] == [
        (stored["run_id"], "live", "WLAN_NB_SPL0_LIVE", 4, "ok"),
        (again["run_id"], "live", "WLAN_NB_SPL0_LIVE", 4, "ok"),
        (sim["run_id"], "sim", "WLAN_NB_SPL0", 4, "ok"),
    ]
    assert rows[0][5] == pytest.approx(live["mission"]["total_distance"])
    assert rows[0][6] == live["mission"]["tasks_completed"] == 3
    assert json.loads(options_json)["speed"] == 10.0 and counts > 0


def test_a_bad_db_is_refused_before_any_process_starts(tmp_path: Path) -> None:
    bad = tmp_path / "bad.duckdb"
    bad.write_text("hello\n")
    records = tmp_path / "records"
    done = mrcomm("live", str(S1), "--db", str(bad), "--record-dir", str(records), timeout=30)
    one_line_error(done, str(bad), "damaged or not a DuckDB database")
    assert not records.exists()  # nothing launched, nothing recorded
    done = mrcomm("collect", str(records), "--db", str(bad), timeout=30)
    one_line_error(done, "damaged or not a DuckDB database")
    assert bad.read_text() == "hello\n"
