"""A frame on the shared channel against the other frames on the air: its payload cut
into chunks at the instants they start or end during it, and each chunk judged at its
own SINR — how ns-3's interference helper judges a frame, so that two interferers one
after the other are never counted as if they had been on the air at once.

Compiled where numba is there (:mod:`mrcomm.compiled`), like the event loop of
:mod:`mrcomm.net.radio.air` that calls it.
"""

from __future__ import annotations

import math
from typing import Any

from mrcomm.compiled import compiled
from mrcomm.net.radio.reception import bit_error, decibels

#: Two instants closer than this (s) are the same instant (slot boundaries are sums).
SAME_TIME_S = 1e-12


@compiled
def chunked_error(
    power_dbm: float, chunk_bits: Any, chunk_mw: Any, r: int, noise_mw: float, dsss: bool
) -> float:
    """Probability that a frame received at ``power_dbm`` (its preamble already detected)
    is lost at receiver ``r`` (a column of ``chunk_mw``): the bits of each chunk meet the
    BER at that chunk's SINR, the noise floor ``noise_mw`` plus the other frames on the
    air through it. One chunk of all the bits gives PER = 1 − (1 − BER)^bits."""
    kept = 0.0  # log of the probability that every bit so far survived
    for c in range(chunk_bits.shape[0]):
        rate = bit_error(power_dbm - decibels(noise_mw + chunk_mw[c, r]), dsss, math.nan, False)
        if rate >= 1.0:
            return 1.0
        if rate > 0.0:
            kept += chunk_bits[c] * math.log1p(-rate)
    if kept == 0.0:
        return 0.0
    return -math.expm1(kept)


@compiled
def cut(
    f: int, payload_start: float, window: Any, size: int, start: Any, end: Any, bits: Any,
    frame_mw: Any, chunk_bits: Any, chunk_mw: Any, base: int, times: Any, over: Any,
) -> int:  # fmt: skip
    """Cut frame ``f``'s payload (``payload_start`` to its end: the preamble was judged
    when it started) at the instants the frames of ``window[:size]`` that overlap it
    start or end, into ``chunk_bits`` and ``chunk_mw`` from index ``base``: each chunk's
    share of the bits and the power of the frames on the air through it at each receiver
    (mW, summed in the window's order). Returns how many chunks; ``times`` and ``over``
    are work arrays (twice and once the window)."""
    n = frame_mw.shape[1]
    a = payload_start
    b = end[f]
    overlapping = 0
    cuts = 0
    for j in range(size):
        g = window[j]
        if g != f and start[g] < b - SAME_TIME_S and end[g] > a + SAME_TIME_S:
            over[overlapping] = g
            overlapping += 1
            for t in (start[g], end[g]):
                if not a + SAME_TIME_S < t < b - SAME_TIME_S:
                    continue
                # Into the sorted instants, once.
                k = cuts
                while k > 0 and times[k - 1] > t:
                    k -= 1
                if (k > 0 and t - times[k - 1] <= SAME_TIME_S) or (
                    k < cuts and times[k] - t <= SAME_TIME_S
                ):
                    continue
                for i in range(cuts, k, -1):
                    times[i] = times[i - 1]
                times[k] = t
                cuts += 1
    length = b - a
    lo = a
    for i in range(cuts + 1):
        hi = times[i] if i < cuts else b
        c = base + i
        # (One chunk keeps exactly the frame's bits: (b − a) / (b − a) is 1.)
        chunk_bits[c] = bits[f] * ((hi - lo) / length) if length > 0.0 else float(bits[f])
        middle = 0.5 * (lo + hi)
        for r in range(n):
            chunk_mw[c, r] = 0.0
        for k in range(overlapping):
            g = over[k]
            if start[g] < middle < end[g]:
                for r in range(n):
                    chunk_mw[c, r] += frame_mw[g, r]
        lo = hi
    return cuts + 1
