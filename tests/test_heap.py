"""The heap keeps freed blocks: a large block allocated again faults no fresh pages."""

from __future__ import annotations

import subprocess
import sys

import pytest

#: Allocates three 2 MiB numpy arrays and frees them, 50 times (writing every page, as a
#: search does with its grid-sized arrays), and prints the page faults that took; with
#: ``keep`` the heap thresholds are set first. (Three: glibc's own adaptive threshold
#: keeps one freed block of a size it has seen, not the several a search frees at once.)
CHILD = """
import resource, sys
import numpy as np
from mrcomm.heap import keep_freed_blocks
if sys.argv[1] == "keep":
    assert keep_freed_blocks()
np.ones(1 << 18)  # numpy's own first-use allocations, before counting
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(50):
    blocks = [np.ones(1 << 18) for _ in range(3)]  # 2 MiB each, every page written
    del blocks
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults(mode: str) -> int:
    done = subprocess.run(
        [sys.executable, "-c", CHILD, mode], capture_output=True, text=True, check=True
    )
    return int(done.stdout.strip())


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt: Linux only")
def test_a_freed_block_is_reused_without_fresh_page_faults() -> None:
    kept = _faults("keep")
    default = _faults("default")
    # 150 blocks of 512 pages: fresh pages fault ~75,000 times, kept blocks once each.
    assert kept < 2_000, (kept, default)
    assert default > 20_000, (kept, default)  # what keeping them saves
