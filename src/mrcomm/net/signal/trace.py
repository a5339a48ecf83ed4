"""Replay of a recorded RSSI trace (ESD in simulation).

A trace is a CSV with columns ``time`` (s since mission start), ``from`` (the robot that
measured), ``to`` (the peer it measured) and ``rssi`` (dBm); ``#`` lines are comments.
:meth:`RssiTrace.matrix_at` gives, for a list of robot ids, the n × n matrix of the last
reading at or before ``t`` (zero-order hold) — row = measuring robot, column = peer —
with NaN where there is none (no reading yet, unknown pair, diagonal).

Lookup is vectorised: readings are sorted by (pair, time) and offset per pair into one
increasing array, so a single ``searchsorted`` answers every pair at once.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mrcomm.errors import InputError
from mrcomm.net.signal.csvio import read_csv

COLUMNS = ("time", "from", "to", "rssi")
FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


#: Latest reading time accepted (s, about 115 days): readings are looked up by time
#: plus an offset per pair in one float array, exact to well under a millisecond only
#: while the times stay this small (a trace spanning 1e20 s looked up wrong readings).
MAX_TRACE_S = 1e7


@dataclass(eq=False)
class RssiTrace:
    """Readings of directed pairs over time, ready for zero-order-hold lookup."""

    pairs: tuple[tuple[str, str], ...]  # pair index -> (from, to)
    keys: FloatArray  # (time - t0) + pair * stride, increasing
    rssi: FloatArray
    start: IntArray  # first reading index of each pair
    t0: float
    t1: float
    stride: float
    _pair_index: dict[tuple[str, str], int] = field(default_factory=dict, repr=False)
    _cache: dict[tuple[str, ...], tuple[IntArray, IntArray, IntArray]] = field(
        default_factory=dict, repr=False
    )

    @classmethod
    def from_readings(
        cls,
        times: ArrayLike,
        sources: Sequence[str],
        targets: Sequence[str],
        rssi: ArrayLike,
    ) -> RssiTrace:
        """Build from parallel sequences (later duplicates of a time win)."""
        t = np.asarray(times, dtype=np.float64)
        r = np.asarray(rssi, dtype=np.float64)
        if not (t.size == r.size == len(sources) == len(targets)) or t.size == 0:
            raise ValueError("need one or more readings, all sequences the same length")
        pair_index: dict[tuple[str, str], int] = {}
        p = np.array(
            [
                pair_index.setdefault((a, b), len(pair_index))
                for a, b in zip(sources, targets, strict=True)
            ],
            dtype=np.intp,
        )
        order = np.lexsort((t, p))  # stable: equal times keep file order
        t0, t1 = float(t.min()), float(t.max())
        stride = (t1 - t0) + 1.0
        keys = (t[order] - t0) + p[order] * stride
        start = np.searchsorted(p[order], np.arange(len(pair_index)), side="left")
        pairs = tuple(pair_index)
        return cls(pairs, keys, r[order], start.astype(np.intp), t0, t1, stride, pair_index)

    @classmethod
    def load(cls, path: str | Path) -> RssiTrace:
        """Read a trace CSV; errors name the file, line and column."""
        table = read_csv(path, COLUMNS)
        if not table.rows:
            raise InputError("no readings", file=table.path)
        times, sources, targets, values = [], [], [], []
        for lineno, row in table.rows:
            time = table.number(lineno, row, "time")
            if not 0.0 <= time <= MAX_TRACE_S:
                limit = f"{MAX_TRACE_S:g}"
                raise table.error(lineno, "time", f"{time:g} s is not within 0-{limit} s")
            times.append(time)
            for column in ("from", "to"):
                if not row[column]:
                    raise table.error(lineno, column, "empty robot id")
            if row["from"] == row["to"]:
                raise table.error(lineno, "to", f"reading of {row['from']!r} by itself")
            sources.append(row["from"])
            targets.append(row["to"])
            values.append(table.number(lineno, row, "rssi"))
        return cls.from_readings(times, sources, targets, values)

    @property
    def robots(self) -> list[str]:
        """Every robot id that appears in the trace."""
        return sorted({rid for pair in self.pairs for rid in pair})

    def matrix_at(self, t: float, ids: Sequence[str]) -> FloatArray:
        """RSSI[i, j] measured by ``ids[i]`` of ``ids[j]``: last reading at or before
        ``t``, NaN if none."""
        if t != t:
            raise ValueError("time is NaN")
        n = len(ids)
        out = np.full((n, n), np.nan)
        rows, cols, pair = self._pairs_for(tuple(ids))
        if pair.size == 0 or t < self.t0:
            return out
        # Clamp so a late query cannot spill into the next pair's block of keys.
        query = (min(t, self.t1) - self.t0) + pair * self.stride
        pos = np.searchsorted(self.keys, query, side="right") - 1
        valid = pos >= self.start[pair]
        out[rows[valid], cols[valid]] = self.rssi[pos[valid]]
        return out

    def _pairs_for(self, ids: tuple[str, ...]) -> tuple[IntArray, IntArray, IntArray]:
        cached = self._cache.get(ids)
        if cached is None:
            found = [
                (i, j, self._pair_index[(a, b)])
                for i, a in enumerate(ids)
                for j, b in enumerate(ids)
                if (a, b) in self._pair_index
            ]
            arr = np.array(found, dtype=np.intp).reshape(-1, 3)
            cached = (arr[:, 0], arr[:, 1], arr[:, 2])
            self._cache[ids] = cached
        return cached
