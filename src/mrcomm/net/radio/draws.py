"""The shared channel's random streams, drawn ahead: numpy's draws, taken in a compiled
loop from 64-bit draws of each node's generator made before the loop.

The loop of :mod:`mrcomm.net.radio.air` needs a uniform draw for each frame's arrival and
a backoff counter at each access. A numba function cannot call a numpy ``Generator``,
so the caller (:class:`~mrcomm.net.radio.medium.SharedMedium`) draws each node's raw
64-bit numbers ahead (``bit_generator.random_raw``) and the loop turns them into exactly
what ``random()`` and ``integers(0, k + 1)`` would have given on that generator, in the
same order: the channel alone draws from these streams, so its results are the ones
drawing one value at a time would give (``tests/net/test_air.py``).

``streams`` is a tuple: the 64-bit draws per node (a row each), how many each has used,
how many it has, and PCG64's kept half (whether it has one, and its value): a 64-bit draw
serves two 32-bit ones.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mrcomm.compiled import compiled

#: numpy's doubles: the top 53 bits of a 64-bit draw, scaled to [0, 1).
_DOUBLE = 1.0 / 9007199254740992.0
_LOW32 = np.uint64(0xFFFFFFFF)


@compiled
def _raw(node: int, streams: Any) -> Any:
    """The next 64-bit draw of ``node``'s stream (drawn ahead by the caller)."""
    raw, position, length = streams[0], streams[1], streams[2]
    if position[node] >= length[node]:
        raise RuntimeError("shared channel: a node ran out of random numbers")
    value = raw[node, position[node]]
    position[node] += 1
    return value


@compiled
def uniform(node: int, streams: Any) -> float:
    """A uniform draw in [0, 1) from ``node``'s stream, as numpy's ``random()``."""
    return float(_raw(node, streams) >> np.uint64(11)) * _DOUBLE


@compiled
def _next32(node: int, streams: Any) -> Any:
    """32 bits of ``node``'s stream, as PCG64 gives them: each 64-bit draw serves two
    (the low half first)."""
    has_half, half = streams[3], streams[4]
    if has_half[node]:
        has_half[node] = False
        return half[node]
    value = _raw(node, streams)
    has_half[node] = True
    half[node] = value >> np.uint64(32)
    return value & _LOW32


@compiled
def bounded(node: int, streams: Any, largest: int) -> int:
    """An integer uniform in 0..``largest`` from ``node``'s stream: numpy's
    ``integers(0, largest + 1)`` (Lemire's method for bounded integers, which draws
    nothing for a single value), so the same values."""
    if largest == 0:
        return 0
    excl = np.uint64(largest + 1)
    m = _next32(node, streams) * excl
    leftover = m & _LOW32
    if leftover < excl:
        threshold = (_LOW32 - np.uint64(largest)) % excl
        while leftover < threshold:
            m = _next32(node, streams) * excl
            leftover = m & _LOW32
    return int(m >> np.uint64(32))
