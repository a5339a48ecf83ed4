"""Nothing left behind: SIGKILL of ``mrcomm live`` takes every process it started with
it, and the throwaway team's keys it could not remove are removed by the next run."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from mrcomm.live.identity import throwaway_team
from mrcomm.live.leftovers import TEAM_PREFIX, alive

from .helpers import S1, journal, wait_for

pytestmark = pytest.mark.slow


def processes_mentioning(text: str) -> list[int]:
    """Every process whose command line contains ``text``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if text in cmdline:
            found.append(int(entry.name))
    return found


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux's parent-death signal")
def test_sigkill_of_the_launcher_leaves_no_process_and_no_key(tmp_path: Path) -> None:
    record = tmp_path / "records"
    code = "from mrcomm.cli.main import app; app()"
    launcher = subprocess.Popen(
        [sys.executable, "-c", code, "live", str(S1), "--speed", "1", "--record-dir", str(record)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
    )  # fmt: skip
    try:
        wait_for(
            lambda: any(line.get("k") == "first_tick" for line in journal(record, "robot_*")),
            90, "the mission to start",
        )  # fmt: skip
        children = [p for p in processes_mentioning(str(record)) if p != launcher.pid]
        assert len(children) >= 4, children  # the world and three robots
        keys = list(Path(tempfile.gettempdir()).glob(f"{TEAM_PREFIX}{launcher.pid}-*"))
        assert len(keys) == 1 and (keys[0] / "team").is_dir()
        os.kill(launcher.pid, signal.SIGKILL)
        launcher.wait(timeout=10)
        wait_for(lambda: not any(alive(p) for p in children), 30, "every child to end")
        assert keys[0].exists()  # killed: it could not remove them ...
        with throwaway_team(None, False, ["robot_1"]):  # ... the next run does
            assert not keys[0].exists()
    finally:
        if launcher.poll() is None:
            os.killpg(launcher.pid, signal.SIGKILL)
            launcher.wait()
        for pid in processes_mentioning(str(record)):  # a failed test leaves no orphan
            os.kill(pid, signal.SIGKILL)
