"""`mrcomm analyze` and `mrcomm report` on a real swept database: the three output
formats, the report files, and bad input as one line with exit status 2."""

from __future__ import annotations

import io
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import pytest

from mrcomm.analysis import stats as st
from mrcomm.cli.main import app
from tests.analysis.conftest import mrcomm, study_db  # noqa: F401  (session fixture)


@dataclass
class Outcome:
    returncode: int
    stdout: str
    stderr: str


def in_process(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, *args: str
) -> Outcome:
    """``mrcomm ARGS`` through the console-script entry, without a new interpreter."""
    monkeypatch.setattr(sys, "argv", ["mrcomm", *args])
    with pytest.raises(SystemExit) as stop:
        app()
    out = capsys.readouterr()
    return Outcome(int(stop.value.code or 0), out.out, out.err)


def test_analyze_csv_is_the_statistics(
    study_db: Path,  # noqa: F811
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    proc = in_process(
        capsys,
        monkeypatch,
        "analyze",
        "--db",
        str(study_db),
        "--metric",
        "execution_phase_time",
        "--table",
        "comparisons",
        "--table",
        "success_counts",
        "--format",
        "csv",
    )
    assert proc.returncode == 0, proc.stderr
    blocks = proc.stdout.split("# ")[1:]
    assert [b.splitlines()[0] for b in blocks] == ["comparisons", "success_counts"]
    table = pd.read_csv(io.StringIO(blocks[0].split("\n", 1)[1]))
    from mrcomm.experiment.api import load_results

    runs = load_results(study_db).runs
    direct = st.comparison_table(runs, ["execution_phase_time"])
    assert list(table["behaviour"]) == list(direct["behaviour"]) == ["lf", "nb"]
    assert table["u"].tolist() == direct["u"].tolist()
    assert table["p"].tolist() == pytest.approx(direct["p"].tolist())


def test_analyze_table_and_latex(
    study_db: Path,  # noqa: F811
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    proc = in_process(
        capsys, monkeypatch, "analyze", "--db", str(study_db), "--metric", "total_distance"
    )
    assert proc.returncode == 0, proc.stderr
    for title in ("Mann–Whitney", "Shapiro–Wilk", "Descriptive", "Successful", "Chi-squared"):
        assert title.replace("–", "-") in proc.stdout.replace("–", "-"), title
    assert "AH+SLT+LF" in proc.stdout and "total_distance" in proc.stdout
    latex = in_process(
        capsys,
        monkeypatch,
        "analyze",
        "--db",
        str(study_db),
        "--format",
        "latex",
        "--table",
        "normality",
        "--metric",
        "delay_time",
    )
    assert latex.returncode == 0, latex.stderr
    assert latex.stdout.count(r"\begin{tabular}") == 1 and "delay\\_time" in latex.stdout


def test_report_command_writes_the_report(study_db: Path, tmp_path: Path) -> None:  # noqa: F811
    out = tmp_path / "report"
    proc = mrcomm(
        "report",
        "--db",
        str(study_db),
        "--out",
        str(out),
        "--metric",
        "execution_phase_time",
        "--no-svg",
    )
    assert proc.returncode == 0, proc.stderr
    assert str(out / "report.html") in proc.stdout
    html = (out / "report.html").read_text()
    assert html.count('<img src="data:image/png;base64,') == len(list(out.glob("figures/*.png")))
    assert not list(out.glob("figures/*.svg"))
    assert (out / "tables" / "comparisons.csv").is_file()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["analyze", "--db", "{db}", "--format", "xlsx"], "--format: unknown format 'xlsx'"),
        (["analyze", "--db", "{db}", "--metric", "delay"], "did you mean 'delay_time'"),
        (["analyze", "--db", "{db}", "--table", "comparison"], "did you mean 'comparisons'"),
        (["analyze", "--db", "{tmp}/missing.duckdb"], "--db: no such results database"),
        (["analyze", "--db", "{tmp}/notadb.duckdb"], "notadb.duckdb"),
        (["report", "--db", "{db}", "--out", "{tmp}/notadb.duckdb"], "not a directory"),
        (["report", "--db", "{db}", "--out", "{tmp}/a/b"], "does not exist"),
        (["report", "--db", "{db}", "--out", "{tmp}/r", "--timeline", "AH-r001"], "--timeline"),
    ],
)
def test_bad_input_is_one_line_exit_2(
    study_db: Path,  # noqa: F811
    tmp_path: Path,
    args: list[str],
    message: str,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    (tmp_path / "notadb.duckdb").write_text("hello")
    argv = [a.format(db=study_db, tmp=tmp_path) for a in args]
    proc = in_process(capsys, monkeypatch, *argv)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert message in proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "r").exists()


def test_analyze_fits_a_100_column_terminal(study_db: Path) -> None:  # noqa: F811
    import os
    import subprocess
    import sys

    env = {**os.environ, "COLUMNS": "100"}
    proc = subprocess.run(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", "analyze", "--db",
         str(study_db)],
        capture_output=True, text=True, env=env, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    widest = max(len(line) for line in proc.stdout.splitlines())
    assert widest <= 100, widest
    assert "H0 not rejected" in proc.stdout and "accepted" not in proc.stdout
