"""Progress of a live mission read from its journals (the recorded golden mission):
the last clock tick, completed tasks, robots present; followed incrementally, a line
still being written is read only once complete. ``mrcomm live`` shows it while it runs,
and Ctrl-C stops every process and says what became of the records."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import tarfile
from pathlib import Path

from mrcomm.live.progress import JournalFollower
from tests.conftest import ROOT

from .helpers import S1
from .test_live_cli import CODE

RECORDS = ROOT / "tests" / "golden" / "live_records.tar.gz"


def _records(tmp_path: Path) -> Path:
    with tarfile.open(RECORDS) as archive:
        archive.extractall(tmp_path, filter="data")
    (directory,) = [p for p in tmp_path.iterdir() if p.is_dir()]
    return directory


def test_progress_of_a_recorded_mission(tmp_path: Path) -> None:
    records = _records(tmp_path)
    state = JournalFollower(records).poll()
    assert state.tasks_done == 7  # the mission completed its 7 tasks
    assert state.robots_alive == 0  # every agent left at the end
    assert set(state.alive) == {"world", "assigner", "robot_1", "robot_2", "robot_3"}
    world = next(records.glob("world.*.jsonl")).read_text().splitlines()
    last_clock = [line for line in world if '"k":"clock"' in line][-1]
    assert last_clock.startswith(f'{{"sim":{state.sim_time},')


def test_journals_are_followed_incrementally(tmp_path: Path) -> None:
    records = _records(tmp_path)
    world = next(records.glob("world.*.jsonl"))
    lines = world.read_bytes().splitlines(keepends=True)
    clock = [i for i, line in enumerate(lines) if b'"k":"clock"' in line]
    cut = clock[10]
    # The first part, then half of the next clock line: read up to the complete lines.
    world.write_bytes(b"".join(lines[: cut + 1]) + lines[clock[11]][:10])
    follower = JournalFollower(records)
    state = follower.poll()
    first = state.sim_time
    assert first == float(lines[cut].split(b'"sim":')[1].split(b",")[0])
    assert state.robots_alive == 3  # mid-mission: the assigner and the world not counted
    world.write_bytes(b"".join(lines[: cut + 1]) + b"".join(lines[cut + 1 :]))
    assert follower.poll().sim_time > first


def _live(tmp_path: Path, *extra: str) -> subprocess.Popen[str]:
    env = {**os.environ, "TMPDIR": str(tmp_path)}

    def default_sigint() -> None:
        # A shell's background job ignores SIGINT, and so would the child: undo it, as
        # a terminal's Ctrl-C reaches a foreground command.
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    return subprocess.Popen(
        [sys.executable, "-c", CODE, "live", str(S1), "--speed", "10", "--max-time", "600", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        preexec_fn=default_sigint,
    )


def _interrupt_after_progress(proc: subprocess.Popen[str]) -> tuple[str, str]:
    """SIGINT once the first plain progress line is out (stderr is not a terminal)."""
    assert proc.stderr is not None
    first = proc.stderr.readline()  # blocks until the first progress line (~10 s)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    return out, first + err


def test_live_shows_progress_and_ctrl_c_removes_temporary_records(tmp_path: Path) -> None:
    proc = _live(tmp_path)
    out, err = _interrupt_after_progress(proc)
    assert re.match(r"live: mission clock \d+/600 s, tasks \d/7 done, robots [0-3]/3 present", err)
    assert proc.returncode == 130 and out == ""
    assert err.splitlines()[-1] == (
        "mrcomm: interrupted; every process stopped, the partial records removed"
    )
    assert not list(tmp_path.glob("mrcomm-live-*"))  # nothing left in the temporary dir


def test_ctrl_c_keeps_records_in_a_given_directory(tmp_path: Path) -> None:
    records = tmp_path / "records"
    proc = _live(tmp_path, "--record-dir", str(records))
    _, err = _interrupt_after_progress(proc)
    assert proc.returncode == 130
    assert err.splitlines()[-1].endswith(f"the partial records kept in {records}")
    assert list(records.glob("world.*.jsonl"))
    # Every world and agent process stopped (their command lines name the records).
    assert subprocess.run(["pgrep", "-f", str(records)], capture_output=True).stdout == b""
