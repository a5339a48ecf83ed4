"""The C heap of this process: keep freed blocks for reuse instead of handing them back
to the operating system.

glibc serves a request of more than 128 KiB with fresh pages from ``mmap`` and returns
them on ``free``; every page of such a block then faults when first written. The planner
allocates blocks of that size on every search (pyastar2d: a cost and a parent array over
the planning grid), and numpy does for any large temporary (a link model's distance
matrix in a team of 1,000). On a 400 x 600 cell grid a search that expands a handful of
cells took 0.48 ms, 0.46 ms of it page faults; with freed blocks kept on the heap it
takes 0.02 ms (``benchmarks/bench_heap.py``). :func:`keep_freed_blocks` tells glibc to
serve blocks up to :data:`MMAP_THRESHOLD` from the heap and to keep up to
:data:`TRIM_THRESHOLD` of free memory at its top. Nothing computed changes; a process
keeps a little more memory mapped than it uses. Elsewhere than glibc it does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import sys

#: Blocks up to this size (bytes) come from the heap (32 MiB, glibc's largest).
MMAP_THRESHOLD = 32 * 1024 * 1024
#: Free memory at the top of the heap up to this size (bytes) is kept, not returned.
TRIM_THRESHOLD = 128 * 1024 * 1024
_M_TRIM_THRESHOLD = -1  # from glibc's malloc.h
_M_MMAP_THRESHOLD = -3

_done: bool | None = None


def keep_freed_blocks() -> bool:
    """Set the thresholds once per process; True when they are set (glibc)."""
    global _done
    if _done is None:
        _done = _set_thresholds()
    return _done


def _set_thresholds() -> bool:
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # not glibc (musl has no mallopt)
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    # Both, or glibc's own adaptive threshold would keep returning the blocks.
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(
        mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    )
