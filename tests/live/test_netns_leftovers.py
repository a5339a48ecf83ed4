"""The namespaces of an emulated run killed before it could delete them are deleted by
the next emulated run (``remove_stale_namespaces``, called before it makes its own);
those of a run still going are left alone. Real namespaces (root), skipped otherwise."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from mrcomm.live.netns import NETNS_PREFIX, remove_stale_namespaces, run_tool

from .netns import skip_unless_possible

pytestmark = [pytest.mark.alone]


def namespaces() -> set[str]:
    return {line.split(" ", 1)[0] for line in run_tool("ip", "netns", "list").splitlines()}


def test_a_killed_runs_namespaces_are_removed_by_the_next() -> None:
    skip_unless_possible()
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    dead = int(gone.stdout)  # a process that has ended
    stale = [f"{NETNS_PREFIX}{dead}hub", f"{NETNS_PREFIX}{dead}n0"]
    ours = f"{NETNS_PREFIX}{os.getpid()}n0"  # a run still going (this process)
    for name in (*stale, ours):
        run_tool("ip", "netns", "add", name)
    run_tool("ip", "netns", "exec", stale[1], "nft", "add", "table", "inet", "mrcomm")
    try:
        removed = remove_stale_namespaces()
        assert set(stale) <= set(removed) and ours not in removed
        assert not set(stale) & namespaces() and ours in namespaces()
    finally:
        for name in (*stale, ours):
            subprocess.run(["ip", "netns", "del", name], capture_output=True)
