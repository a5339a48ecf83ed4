"""A sweep killed outright (SIGKILL of the sweep process only, as an OOM killer or a
cluster's time limit does) takes its workers with it: nothing keeps running a run that
nobody will store."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import S1_PATH
from tests.experiment.helpers import write_schema
from tests.live.helpers import wait_for

LONG = f"""\
name: long
scenario: {S1_PATH}
repetitions: 40
base_seed: 5
factors:
  network: [ah]
  spl: [0]
  behaviour: [nb]
  threshold: slt
"""


def session_members(sid: int) -> list[int]:
    """Pids of the processes in session ``sid`` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        if int(fields[3]) == sid:  # field 6 of stat: the session id
            found.append(int(entry.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_workers_end_when_the_sweep_is_killed(tmp_path: Path) -> None:
    schema = write_schema(tmp_path, LONG, "long.yaml")
    sweep = subprocess.Popen(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", "sweep", str(schema),
         "--db", str(tmp_path / "r.duckdb"), "--jobs", "2"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
    )  # fmt: skip
    try:
        # The sweep, its pool's fork server and two workers.
        wait_for(lambda: len(session_members(sweep.pid)) >= 4, 60, "the workers")
        os.kill(sweep.pid, signal.SIGKILL)
        sweep.wait(timeout=10)
        wait_for(lambda: not session_members(sweep.pid), 30, "the workers to end")
    finally:
        for pid in session_members(sweep.pid):
            os.kill(pid, signal.SIGKILL)


def test_a_resumed_sweep_removes_what_a_killed_one_left_of_its_recordings(
    tmp_path: Path,
) -> None:
    from mrcomm.experiment.schema import load_experiment
    from tests.experiment.helpers import MINI

    schema = write_schema(tmp_path, MINI)
    record = tmp_path / "rec"
    record.mkdir()
    run_ids = [spec.run_id for spec in load_experiment(schema).runs(1)]
    partial = record / f".{run_ids[0]}.mcap.x1y2z3.tmp"  # as fileio.stage names it
    partial.write_bytes(b"half a recording")
    other = record / "notes.txt"
    other.write_text("not ours")
    done = subprocess.run(
        [sys.executable, "-c", "from mrcomm.cli.main import app; app()", "sweep", str(schema),
         "--db", str(tmp_path / "r.duckdb"), "--reps", "1", "--jobs", "1", "--record", str(record)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert not partial.exists() and other.read_text() == "not ours"
    assert sorted(p.name for p in record.glob("*.mcap")) == sorted(f"{r}.mcap" for r in run_ids)
