"""MRComm installed as a package, the way a plugin author or a notebook user gets it: a
wheel built from this repository, installed in a fresh virtual environment outside it
(its dependencies from the package index, as ``make`` installs them), run from an empty
directory. The bundled data must come with it: S1 by name with SSD's bundled model and
with ESD's bundled trace, ``mrcomm check behaviour.nb``, a small sweep of the bundled
demo experiment, its report, and its Parquet export read back by pandas."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import venv
from pathlib import Path

import pytest

from tests.conftest import ROOT

pytestmark = pytest.mark.slow


def _run(*args: str | Path, cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    proc = subprocess.run([str(a) for a in args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)  # fmt: skip
    assert proc.returncode == 0, f"{args}: exit {proc.returncode}\n{proc.stdout}\n{proc.stderr}"
    return proc


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The bin directory of a fresh environment holding the wheel of this checkout."""
    base = tmp_path_factory.mktemp("wheel")
    wheels = base / "dist"
    _run(sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", wheels, ROOT, cwd=base)
    (wheel,) = wheels.glob("mrcomm-*.whl")
    env = base / "env"
    venv.create(env, with_pip=True)
    _run(env / "bin" / "python", "-m", "pip", "install", "-q", wheel, cwd=base)
    return env / "bin"


@pytest.fixture
def elsewhere(tmp_path: Path) -> Path:
    """An empty working directory outside the repository."""
    assert ROOT not in tmp_path.resolve().parents
    return tmp_path


def test_the_package_is_the_wheel_not_the_checkout(installed: Path, elsewhere: Path) -> None:
    out = _run(installed / "python", "-c",
               "import mrcomm, mrcomm.bundled as b; print(mrcomm.__file__); print(b.data_root())",
               cwd=elsewhere).stdout.split()  # fmt: skip
    assert all(str(installed.parent) in line for line in out), out
    assert all(str(ROOT) not in line for line in out), out


def test_s1_by_name_with_ssd_and_with_esd_trace(installed: Path, elsewhere: Path) -> None:
    mrcomm = installed / "mrcomm"
    ssd = _run(mrcomm, "run", "s1", "--network", "ah", "--threshold", "ssd", "--behaviour",
               "lf", "--json", cwd=elsewhere)  # fmt: skip
    assert json.loads(ssd.stdout)["mission"]["successful"] is True
    esd = _run(mrcomm, "run", "s1", "--network", "ah", "--threshold", "esd", "--rssi-trace",
               "s1_synthetic_esd", "--behaviour", "lf", "--json", cwd=elsewhere)  # fmt: skip
    result = json.loads(esd.stdout)
    assert result["mission"]["successful"] is True
    assert result["config"]["params"]["threshold"]["trace"].endswith("s1_synthetic_esd.csv")


def test_conformance_check_passes(installed: Path, elsewhere: Path) -> None:
    out = _run(installed / "mrcomm", "check", "behaviour.nb", cwd=elsewhere).stdout
    assert "every check passed" in out and "fail" not in out


def test_bundled_scenario_is_listed_and_copied(installed: Path, elsewhere: Path) -> None:
    mrcomm = installed / "mrcomm"
    listing = _run(mrcomm, "scenario", "list", cwd=elsewhere).stdout
    assert all(f"  {name} " in listing for name in ("s1", "s2", "s3", "s4", "campus1000", "demo"))
    _run(mrcomm, "scenario", "copy", "s2", "mine", cwd=elsewhere)
    assert {p.name for p in (elsewhere / "mine").iterdir()} == {
        "s2.yaml", "s2_tasks.yaml", "s2_map.yaml", "s2_map.png"
    }  # fmt: skip
    _run(mrcomm, "run", "mine/s2.yaml", "--max-time", "20", cwd=elsewhere)


def test_sweep_report_and_parquet_for_pandas(installed: Path, elsewhere: Path) -> None:
    mrcomm = installed / "mrcomm"
    _run(mrcomm, "sweep", "demo", "--reps", "1", "--db", "r.duckdb", "--jobs", "2", cwd=elsewhere)
    _run(mrcomm, "report", "--db", "r.duckdb", "--out", "report", cwd=elsewhere)
    assert (elsewhere / "report" / "report.html").stat().st_size > 10_000
    _run(mrcomm, "export", "--db", "r.duckdb", "--format", "parquet", "--out", "pq", cwd=elsewhere)
    rows = _run(installed / "python", "-c",
                "import pandas; print(len(pandas.read_parquet('pq/runs.parquet')))",
                cwd=elsewhere).stdout  # fmt: skip
    assert int(rows) == 4
