"""A full disk stops a sweep at once, with one line naming the cause (it used to show
as "TransactionException: cannot rollback" and go on through every remaining run).

The disk is a real one: a small tmpfs this test mounts (root, Linux), filled up."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from mrcomm.experiment.store import inspect_database
from tests.conftest import ROOT
from tests.experiment.helpers import MINI, write_schema

MRCOMM = [sys.executable, "-c", "from mrcomm.cli.main import app; app()"]


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    where = tmp_path / "disk"
    where.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("mounting a tmpfs needs root and mount(8)")
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=8M", "tmpfs", str(where)],
                          capture_output=True, text=True)  # fmt: skip
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], check=False)


def fill(disk: Path) -> None:
    """Take every free byte of the disk."""
    with contextlib.suppress(OSError), (disk / "filler").open("wb") as out:
        while True:
            out.write(b"\0" * 65536)
            out.flush()


def test_a_full_disk_stops_the_sweep_at_once(tmp_path: Path, small_disk: Path) -> None:
    schema = write_schema(tmp_path, MINI.replace("max_time: 30", "max_time: 10"))
    db = small_disk / "results.duckdb"
    first = subprocess.run([*MRCOMM, "sweep", str(schema), "--db", str(db), "--jobs", "1",
                            "--reps", "1"], capture_output=True, text=True, cwd=ROOT,
                           timeout=600)  # fmt: skip
    stored = inspect_database(db).runs if first.returncode == 0 else {}
    fill(small_disk)
    done = subprocess.run([*MRCOMM, "sweep", str(schema), "--db", str(db), "--jobs", "1"],
                          capture_output=True, text=True, cwd=ROOT, timeout=600)  # fmt: skip
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 1, done.stderr[-2000:]
    assert lines[-1].startswith("mrcomm: error: cannot"), lines
    assert "No space left on device" in lines[-1] or "space" in lines[-1].lower(), lines[-1]
    assert "Traceback" not in done.stderr
    # It stopped at the first run it could not store: not one line per remaining run.
    assert done.stdout.count("\n") <= 2, done.stdout
    (small_disk / "filler").unlink()
    assert inspect_database(db).runs == stored  # what was stored is intact
