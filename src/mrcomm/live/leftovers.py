"""Nothing left behind by a live run, even one killed hard.

* Every process the launcher starts dies with it: the kernel sends it SIGTERM when the
  launcher's process ends, however it ends (SIGKILL included; Linux ``prctl``
  ``PR_SET_PDEATHSIG``), and each stops cleanly on SIGTERM.
* A throwaway team (its CA and member keys, in a private temporary directory) is named
  after the process that made it; a run that was killed before it could remove it
  leaves it, and the next ``mrcomm live`` of the same user removes every such directory
  whose process has gone (:func:`remove_stale_teams`).
"""

from __future__ import annotations

import ctypes
import os
import re
import shutil
import signal
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

#: A throwaway team's directory: ``mrcomm-team-<pid of its maker>-<random>``.
TEAM_PREFIX = "mrcomm-team-"
_TEAM_DIR = re.compile(rf"^{TEAM_PREFIX}(\d+)-")
_PR_SET_PDEATHSIG = 1


def team_prefix() -> str:
    """The prefix of a throwaway team directory made by this process."""
    return f"{TEAM_PREFIX}{os.getpid()}-"


def die_with_parent() -> Callable[[], None] | None:
    """What a child runs between fork and exec to get SIGTERM when its parent's process
    ends (Linux; None elsewhere). The C function is looked up here, in the parent: the
    child only calls it (nothing that could wait on a lock another thread held)."""
    if not sys.platform.startswith("linux"):
        return None
    prctl = ctypes.CDLL(None, use_errno=True).prctl

    def child() -> None:
        prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)

    return child


def alive(pid: int) -> bool:
    """Whether a process ``pid`` exists."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's: exists
        return True
    return True


def remove_stale_teams(where: Path | None = None) -> list[Path]:
    """Remove the throwaway teams of this user whose maker has gone (killed before it
    could remove them); the directories removed."""
    folder = Path(where or tempfile.gettempdir())
    removed: list[Path] = []
    for path in folder.glob(f"{TEAM_PREFIX}*"):
        match = _TEAM_DIR.match(path.name)
        try:
            mine = path.is_dir() and path.stat().st_uid == os.getuid()
        except OSError:
            continue
        if match is None or not mine or alive(int(match.group(1))):
            continue
        shutil.rmtree(path, ignore_errors=True)
        removed.append(path)
    return removed
