"""Every output option is checked before any work: a path under a regular file, a
directory where a file is expected (or a file where a directory is), an extension the
command cannot write, and a directory the user may not write into all end in one line
on stderr, exit status 2, before any simulation, sweep or live process starts, and with
nothing written."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from mrcomm.output_paths import check_output_dir, check_output_file
from tests.cli.test_report_cli import in_process
from tests.conftest import ROOT, S1_PATH

RUN = ("run", str(S1_PATH), "--seed", "1", "--max-time", "5")


@pytest.fixture
def no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail the test if a mission, sweep or live run starts."""

    def forbidden(*_: object, **__: object) -> None:
        raise AssertionError("work started before the outputs were checked")

    import mrcomm.cli.run_cmd
    import mrcomm.experiment.recording
    import mrcomm.experiment.runner
    import mrcomm.live.launcher

    monkeypatch.setattr(mrcomm.cli.run_cmd, "run_mission", forbidden)
    monkeypatch.setattr(mrcomm.experiment.recording, "run_and_record", forbidden)
    monkeypatch.setattr(mrcomm.experiment.runner, "plan_sweep", forbidden)
    monkeypatch.setattr(mrcomm.live.launcher, "run_live", forbidden)


def _tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


# (command args before the path, the option, what the path names, a good suffix)
FILE_OPTIONS = [
    (RUN, "--plot", ".png"),
    (RUN, "--record", ".mcap"),
    (RUN, "--db", ".duckdb"),
    (("sweep", str(ROOT / "data/experiments/demo.yaml")), "--db", ".duckdb"),
    (("live", str(S1_PATH), "--max-time", "5"), "--db", ".duckdb"),
    (("fsm",), "--out", ".svg"),
    (("signal", "plot"), "--out", ".png"),
    (("signal", "fit", str(ROOT / "data/calibration/synthetic_calibration.csv")), "--out", ".json"),
]
DIR_OPTIONS = [
    (("sweep", str(ROOT / "data/experiments/demo.yaml")), "--record"),
    (("report", "--db", "missing.duckdb"), "--out"),
    (("export", "--db", "missing.duckdb"), "--out"),
]


def _file_cases(tmp: Path, suffix: str) -> Iterator[tuple[str, Path, str]]:
    blocker = tmp / "plain.txt"
    blocker.write_text("a regular file\n")
    (tmp / f"taken{suffix}").mkdir()
    yield "under a regular file", blocker / f"x{suffix}", "is not a directory"
    yield "a directory", tmp / f"taken{suffix}", "is a directory"
    yield "bad extension", tmp / "x.txt", "unsupported extension '.txt'"
    yield "missing directory", tmp / "nowhere" / f"x{suffix}", "does not exist"


@pytest.mark.parametrize(("args", "option", "suffix"), FILE_OPTIONS)
def test_bad_output_files_fail_first(
    args: tuple[str, ...],
    option: str,
    suffix: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    no_work: None,
) -> None:
    for _, path, message in _file_cases(tmp_path, suffix):
        before = _tree(tmp_path)
        out = in_process(capsys, monkeypatch, *args, option, str(path))
        assert out.returncode == 2, (path, out.stderr)
        lines = out.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("mrcomm: error:"), out.stderr
        assert option in lines[0] and message in lines[0], lines[0]
        assert _tree(tmp_path) == before  # nothing written, nothing left behind


@pytest.mark.parametrize(("args", "option"), DIR_OPTIONS)
def test_bad_output_directories_fail_first(
    args: tuple[str, ...],
    option: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    no_work: None,
) -> None:
    blocker = tmp_path / "plain.txt"
    blocker.write_text("a regular file\n")
    for path, message in (
        (blocker, "exists and is not a directory"),
        (blocker / "out", "is not a directory"),
    ):
        before = _tree(tmp_path)
        out = in_process(capsys, monkeypatch, *args, option, str(path))
        assert out.returncode == 2, out.stderr
        (line,) = out.stderr.strip().splitlines()
        assert option in line and message in line, line
        assert _tree(tmp_path) == before


def test_record_and_plot_together_leave_nothing_when_one_is_bad(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The real mission would run here if the checks came late: it must not.
    record, plot = tmp_path / "y.mcap", tmp_path / "y.txt"
    out = in_process(capsys, monkeypatch, *RUN, "--record", str(record), "--plot", str(plot))
    assert out.returncode == 2 and "--plot" in out.stderr
    assert _tree(tmp_path) == []


def test_checks_create_nothing(tmp_path: Path) -> None:
    check_output_dir(tmp_path / "report", "--out")
    check_output_file(tmp_path / "x.png", "--plot", (".png",))
    assert _tree(tmp_path) == []


NOBODY = 65534


@pytest.fixture
def read_only_dir() -> Iterator[Path]:
    """A directory nobody but root may write into (the test user is ``nobody``)."""
    if os.geteuid() != 0 or shutil.which("setpriv") is None:
        pytest.skip("needs root and setpriv to run a command as the unprivileged user nobody")
    path = Path(tempfile.mkdtemp(prefix="mrcomm-ro-"))
    path.chmod(0o555)
    try:
        yield path
    finally:
        shutil.rmtree(path)


def as_nobody(*args: str) -> subprocess.CompletedProcess[str]:
    cmd = [
        *("setpriv", f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups"),
        *(sys.executable, "-c", "from mrcomm.cli.main import app; app()", *args),
    ]
    env = {**os.environ, "HOME": "/tmp", "PYTHONDONTWRITEBYTECODE": "1", "MPLBACKEND": "Agg"}
    return subprocess.run(cmd, capture_output=True, text=True, cwd="/", env=env, timeout=120)


@pytest.mark.parametrize(
    ("args", "option", "name"),
    [
        (RUN, "--plot", "x.png"),
        (RUN, "--record", "x.mcap"),
        (RUN, "--db", "x.duckdb"),
        (("sweep", str(ROOT / "data/experiments/demo.yaml")), "--db", "x.duckdb"),
        (
            ("sweep", str(ROOT / "data/experiments/demo.yaml"), "--db", "/tmp/none.duckdb"),
            "--record",
            "recs",
        ),
        (("report", "--db", "missing.duckdb"), "--out", "report"),
        (("export", "--db", "missing.duckdb"), "--out", "tables"),
        (("fsm",), "--out", "fsm.svg"),
    ],
)
def test_unwritable_directory_as_a_normal_user(
    args: tuple[str, ...], option: str, name: str, read_only_dir: Path
) -> None:
    proc = as_nobody(*args, option, str(read_only_dir / name))
    assert proc.returncode == 2, proc.stderr
    (line,) = proc.stderr.strip().splitlines()
    assert option in line and "permission denied" in line, line
    assert list(read_only_dir.iterdir()) == []


def test_a_setting_that_changes_nothing_is_warned_about_once(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    nb = in_process(capsys, monkeypatch, *RUN, "--network", "ah", "--threshold", "slt")
    assert nb.returncode == 0
    assert nb.stderr == (
        "mrcomm: warning: NB ignores the threshold (slt): its runs are those of --threshold "
        "none; the threshold is recorded for link statistics only\n"
    )
    lf = in_process(
        capsys, monkeypatch, *RUN, "--network", "ah", "--threshold", "slt", "--behaviour", "lf"
    )
    assert lf.returncode == 0 and lf.stderr == ""
