"""``--db`` on ``mrcomm run`` (an ad-hoc run stored with mode sim, then reported) and
``--mode`` on ``mrcomm report`` / ``analyze``: a database holding simulated and live
runs is refused unless one mode is picked, so the two are never pooled."""

from __future__ import annotations

import dataclasses
import io
import json
from pathlib import Path

import duckdb
import pandas as pd
import pytest

from mrcomm.experiment.adhoc import store_result
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from tests.cli.test_report_cli import Outcome, in_process
from tests.conftest import S1_PATH

RUN = ("run", str(S1_PATH), "--network", "ah", "--threshold", "slt", "--max-time", "40")


def one_line_error(proc: Outcome, *needles: str) -> None:
    assert proc.returncode == 2, (proc.stdout[-500:], proc.stderr)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("mrcomm: error:"), proc.stderr
    for needle in needles:
        assert needle in lines[0], lines[0]


def test_run_db_then_report_and_mode_selection(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    s1_resources: object,
) -> None:
    db = tmp_path / "r.duckdb"
    stored = []
    for behaviour, seed in (("nb", "1"), ("nb", "1"), ("lf", "2")):
        proc = in_process(
            capsys, monkeypatch, *RUN, "--behaviour", behaviour, "--seed", seed, "--db", str(db),
            "--json",
        )  # fmt: skip
        assert proc.returncode == 0, proc.stderr
        stored.append(json.loads(proc.stdout)["stored"])
    # The same command twice: the same run (deterministic), stored once.
    assert [s["repetition"] for s in stored] == [1, 1, 1]
    assert [s["new"] for s in stored] == [True, False, True]
    assert stored[0]["run_id"] == stored[1]["run_id"]
    assert stored[0]["config_id"] == stored[1]["config_id"] != stored[2]["config_id"]
    assert all(s["mode"] == "sim" and s["experiment"] == "adhoc" for s in stored)
    nb_seed_1 = (*RUN, "--behaviour", "nb", "--seed", "1", "--db", str(db))
    proc = in_process(capsys, monkeypatch, *nb_seed_1)  # human output says what happened
    assert proc.returncode == 0 and f"already stored as {stored[0]['run_id']}" in proc.stdout
    proc = in_process(capsys, monkeypatch, *nb_seed_1, "--keep-duplicate")
    assert proc.returncode == 0 and f"stored as {stored[0]['config_id']}-r002" in proc.stdout
    con = duckdb.connect(str(db), read_only=True)
    assert con.execute("SELECT count(*), min(mode), max(mode) FROM runs").fetchone() == (
        3, "sim", "sim",
    )  # fmt: skip
    con.close()

    out = tmp_path / "report"
    proc = in_process(capsys, monkeypatch, "report", "--db", str(db), "--out", str(out), "--no-svg")
    assert proc.returncode == 0, proc.stderr
    html = (out / "report.html").read_text()
    assert "MRComm study report: adhoc" in html and "live runs" not in html

    # A live run joins the database: sim and live must not be pooled.
    config = make_config(None, scenario=S1_PATH, network="ah", threshold="slt", max_time=40)
    sim = run_mission(config, s1_resources)  # type: ignore[arg-type]
    live = dataclasses.replace(sim, config={**sim.config, "mode": "live", "speed": 10.0})
    store_result(db, live, run_fingerprint="a live record")
    for command in ("report", "analyze"):
        args = [command, "--db", str(db)] + (["--out", str(out)] if command == "report" else [])
        one_line_error(in_process(capsys, monkeypatch, *args), "--mode", "live, sim")
        one_line_error(
            in_process(capsys, monkeypatch, *args, "--mode", "both"), "--mode", "unknown mode"
        )
    live_out = tmp_path / "live-report"
    proc = in_process(
        capsys, monkeypatch, "report", "--db", str(db), "--out", str(live_out), "--mode", "live",
        "--no-svg",
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    html = (live_out / "report.html").read_text()
    assert "MRComm study report: adhoc (live runs" in html
    live_counts = pd.read_csv(live_out / "tables" / "success_counts.csv")
    assert live_counts["runs"].tolist() == [1]  # the live run alone
    proc = in_process(
        capsys, monkeypatch, "analyze", "--db", str(db), "--mode", "sim", "--table",
        "success_counts", "--format", "csv",
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    sim_counts = pd.read_csv(io.StringIO(proc.stdout.split("\n", 1)[1]))
    assert sorted(sim_counts["runs"]) == [1, 2]  # LF once, NB twice (a kept copy): no live run
    proc = in_process(capsys, monkeypatch, "analyze", "--db", str(db), "--mode", "live")
    assert proc.returncode == 0 and proc.stdout.startswith("Live runs"), proc.stderr


def test_bad_db_and_experiment_options_fail_before_the_mission(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    bad = tmp_path / "bad.duckdb"
    bad.write_text("hello\n")
    one_line_error(
        in_process(capsys, monkeypatch, *RUN, "--db", str(bad)), "damaged or not a DuckDB database"
    )
    assert bad.read_text() == "hello\n"
    one_line_error(
        in_process(capsys, monkeypatch, *RUN, "--db", str(tmp_path / "no" / "r.duckdb")),
        "--db",
        "does not exist",
    )
    one_line_error(in_process(capsys, monkeypatch, *RUN, "--experiment", "x"), "add --db")
    one_line_error(
        in_process(capsys, monkeypatch, *RUN, "--db", str(tmp_path / "r.duckdb"), "--experiment",
                   "../x"),
        "--experiment", "not a valid name",
    )  # fmt: skip
    assert not (tmp_path / "r.duckdb").exists()
