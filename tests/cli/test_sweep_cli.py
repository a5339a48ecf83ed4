"""`mrcomm sweep` and `mrcomm export` from the command line: the 12-run baseline and its
no-op rerun, a SIGKILL mid-sweep then resume, failures, and bad input (exit 2, the
database untouched)."""

from __future__ import annotations

import hashlib
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from mrcomm.experiment.runner import execute_sweep, plan_sweep
from mrcomm.experiment.schema import load_experiment
from mrcomm.experiment.store import inspect_database
from tests.conftest import ROOT, S1_PATH
from tests.experiment.helpers import MINI, write_schema

MRCOMM = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]
BASELINE = ROOT / "data" / "experiments" / "baseline.yaml"


def mrcomm(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*MRCOMM, *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=600
    )


def mrcomm_here(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, *args: str | Path
) -> tuple[int, str, str]:
    """The CLI in this process (no interpreter start-up): (exit status, stdout, stderr)."""
    from mrcomm.cli.main import app

    monkeypatch.setattr(sys, "argv", ["mrcomm", *map(str, args)])
    capsys.readouterr()
    with pytest.raises(SystemExit) as info:
        app()
    out, err = capsys.readouterr()
    code = info.value.code
    return (code if isinstance(code, int) else 0), out, err


def _fingerprint(path: Path) -> tuple[str, float]:
    return hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime


@pytest.mark.slow
def test_baseline_with_3_repetitions_fills_12_runs_and_a_rerun_does_none(tmp_path: Path) -> None:
    db = tmp_path / "results.duckdb"
    first = mrcomm("sweep", BASELINE, "--reps", "3", "--jobs", "2", "--db", db)
    assert first.returncode == 0, first.stderr
    assert "baseline: 12 runs (4 configurations x 3 repetitions): 12 new ok, 0 failed" in (
        first.stdout
    )
    runs = inspect_database(db).runs
    assert len(runs) == 12 and set(runs.values()) == {"ok"}
    second = mrcomm("sweep", BASELINE, "--reps", "3", "--jobs", "2", "--db", db)
    assert second.returncode == 0, second.stderr
    assert "0 new ok, 0 failed, 12 already done" in second.stdout
    assert inspect_database(db).runs == runs


def test_runs_over_their_time_limit_are_failures_exit_1(tmp_path: Path) -> None:
    schema = write_schema(tmp_path)
    db = tmp_path / "r.duckdb"
    proc = mrcomm(
        "sweep", schema, "--reps", "1", "--jobs", "1", "--db", db, "--run-timeout", "1e-6"
    )
    assert proc.returncode == 1, proc.stderr
    assert "0 new ok, 4 failed" in proc.stdout and "timeout:" in proc.stdout
    assert set(inspect_database(db).runs.values()) == {"timeout"}


@pytest.mark.parametrize(
    ("change", "args", "expected"),
    [
        (("spl: [0, 50]", "spll: [0, 50]"), (), "unknown factor 'spll' (did you mean 'spl'?)"),
        (("spl: [0, 50]", "spl: []"), (), "empty factorial"),
        (("spl: [0, 50]", "spl: [0, -5]"), (), "factors.spl"),
        ((), ("--jobs", "0"), "--jobs: must be at least 1"),
        ((), ("--jobs", "100000"), "per CPU on this machine), got 100000"),
        ((), ("--reps", "0"), "--reps: must be at least 1"),
        ((), ("--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", "0.5"), "Dask scheduler"),
    ],
)
def test_bad_input_exits_2_and_creates_no_database(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    change: tuple[str, ...],
    args: tuple[str, ...],
    expected: str,
) -> None:
    schema = write_schema(tmp_path, MINI.replace(*change) if change else MINI)
    db = tmp_path / "r.duckdb"
    code, _, err = mrcomm_here(capsys, monkeypatch, "sweep", schema, "--db", db, *args)
    assert code == 2, err
    assert expected in err and "Traceback" not in err and err.startswith("mrcomm: error: ")
    assert err.count("\n") == 1
    assert not db.exists() and not Path(f"{db}.wal").exists()


def test_incompatible_database_exits_2_untouched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import duckdb

    db = tmp_path / "old.duckdb"
    con = duckdb.connect(str(db))
    con.execute("CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT)")
    con.execute("INSERT INTO meta VALUES ('schema_version', '99')")
    con.close()
    before = _fingerprint(db)
    for args in (
        ("sweep", write_schema(tmp_path), "--db", db),
        ("export", "--db", db, "--out", tmp_path / "x"),
    ):
        code, _, err = mrcomm_here(capsys, monkeypatch, *args)
        assert code == 2 and "results schema version '99'" in err, err
    assert _fingerprint(db) == before and not (tmp_path / "x").exists()


def test_export_command_writes_csv(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "r.duckdb"
    with ThreadPoolExecutor(1) as pool:
        exp = load_experiment(write_schema(tmp_path, MINI.replace("max_time: 30", "max_time: 5")))
        execute_sweep(plan_sweep(exp, db, repetitions=1), pool, max_in_flight=1)
    out = tmp_path / "csv"
    code, stdout, err = mrcomm_here(
        capsys, monkeypatch, "export", "--db", db, "--format", "csv", "--out", out
    )
    assert code == 0, err
    assert stdout.startswith("wrote 14 tables")
    header = (out / "runs.csv").read_text().splitlines()[0]
    assert header.startswith("run_id,config_id,experiment,label,scenario,network,spl")
    assert len((out / "runs.csv").read_text().splitlines()) == 5
    code, _, err = mrcomm_here(
        capsys, monkeypatch, "export", "--db", db, "--format", "xlsx", "--out", out
    )
    assert code == 2 and "choose csv or parquet" in err


@pytest.mark.parametrize(
    ("reps", "factors", "needle"),
    [
        (
            "1000000",
            "{spl: [0, 50], behaviour: [nb, lf]}",
            "expands to 4,000,000 runs (4 configurations x 1,000,000 repetitions)",
        ),
        ("100000", "{spl: [0, 50], behaviour: [nb, lf]}", "expands to 400,000 runs"),
        (
            None,
            f"{{max_time: {list(range(100, 500))}, spl: {list(range(400))}}}",
            "the factors multiply to 160,000 configurations; at most 100,000",
        ),
    ],
)
def test_a_sweep_too_large_to_plan_is_refused_before_anything_is_built(
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    reps: str | None,
    factors: str,
    needle: str,
) -> None:
    """``--reps 1000000`` used to build every run in memory (2.3 GB after a minute), and
    factors with many levels multiply past any memory: now counted first and refused in
    one line, no database made."""
    schema = tmp_path / "big.yaml"
    scenario = ROOT / "data" / "scenarios" / "s1.yaml"
    schema.write_text(
        f"name: big\nscenario: {scenario}\nrepetitions: 1\nbase_seed: 1\nfactors: {factors}\n"
    )
    db = tmp_path / "r.duckdb"
    args = ["sweep", schema, "--db", db, *(["--reps", reps] if reps else [])]
    code, out, err = mrcomm_here(capsys, monkeypatch, *args)
    assert code == 2, (out, err)
    assert len(err.strip().splitlines()) == 1 and needle in err, err
    assert not db.exists() and list(tmp_path.iterdir()) == [schema]


def test_the_run_count_limit_itself() -> None:
    from mrcomm.errors import InputError
    from mrcomm.experiment.schema import MAX_RUNS, check_run_count

    check_run_count(1000, 100, Path("x.yaml"))  # exactly the limit: accepted
    assert MAX_RUNS == 1000 * 100
    with pytest.raises(InputError, match="100,001 runs"):
        check_run_count(100_001, 1, Path("x.yaml"))


def _big_schema(
    directory: Path, factors: str, scenario: str = str(S1_PATH), extra: str = ""
) -> Path:
    path = directory / "big.yaml"
    path.write_text(
        f"name: big\nscenario: {scenario}\nrepetitions: 1\nbase_seed: 1\nfactors: {factors}\n"
        f"{extra}"
    )
    return path


@pytest.mark.parametrize(
    ("reps", "scenario", "needle"),
    [
        # 1,000 configurations: each would be built (a RunConfig) before --reps counted.
        ("1000000", str(S1_PATH), "expands to 1,000,000,000 runs (1,000 configurations x"),
        # 200 team sizes x 1,000 levels: no scenario is generated before the count.
        (
            None,
            "{generate: {map: grid, size: 20x15}, robots: " + str(list(range(2, 202))) + ", "
            "tasks: 3}",
            "the factors multiply to 200,000 configurations",
        ),
    ],
)
def test_the_run_count_comes_before_any_scenario_or_configuration_is_built(
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    reps: str | None,
    scenario: str,
    needle: str,
) -> None:
    from mrcomm.experiment import schema as schema_module

    def built(*_: object) -> None:
        raise AssertionError("built before the run count was checked")

    monkeypatch.setattr(schema_module, "_scenarios", built)
    monkeypatch.setattr(schema_module, "_build", built)
    schema = _big_schema(tmp_path, f"{{max_time: {list(range(100, 1100))}}}", scenario)
    args = ["sweep", schema, "--db", tmp_path / "r.duckdb", *(["--reps", reps] if reps else [])]
    code, out, err = mrcomm_here(capsys, monkeypatch, *args)
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, (out, err)
    assert list(tmp_path.iterdir()) == [schema]  # no database, no generated/ directory


def test_excluded_combinations_are_not_counted(tmp_path: Path) -> None:
    """500 of the 1,000 combinations excluded: 500 x 200 repetitions is the limit
    exactly (accepted), one repetition more is refused with the count."""
    from mrcomm.errors import InputError

    schema = _big_schema(
        tmp_path,
        f"{{spl: [0, 50], max_time: {list(range(100, 600))}}}",
        extra="exclude: [{spl: 50}]\n",
    )
    assert len(load_experiment(schema, repetitions=200).configurations) == 500
    with pytest.raises(InputError, match=r"100,500 runs \(500 configurations x 201 rep"):
        load_experiment(schema, repetitions=201)


def test_the_limit_is_stated_where_the_sweep_is_documented(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from mrcomm.experiment.schema import MAX_RUNS

    code, out, _ = mrcomm_here(capsys, monkeypatch, "sweep", "--help")
    assert code == 0 and f"at most {MAX_RUNS:,}" in " ".join(out.split())
    docs = " ".join((ROOT / "docs" / "RESULTS.md").read_text().split())
    assert f"at most {MAX_RUNS:,} runs" in docs
