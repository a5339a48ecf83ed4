"""Calibration sets: RSSI measured at known distances, line of sight or obstructed.

CSV columns ``distance`` (m, ≥ 0), ``rssi`` (dBm) and ``line_of_sight`` (true/false,
1/0, yes/no); ``#`` lines are comments (provenance, e.g. "SYNTHETIC"). Loading checks
everything a model fit needs and reports the first problem in one line naming the
file, line and column.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mrcomm.errors import InputError
from mrcomm.net.signal.csvio import read_csv, write_csv

COLUMNS = ("distance", "rssi", "line_of_sight")
#: Fewest readings per class (line of sight / obstructed) a model may be fitted from.
MIN_READINGS = 10
_TRUE = frozenset({"true", "1", "yes", "y", "t"})
_FALSE = frozenset({"false", "0", "no", "n", "f"})


@dataclass(frozen=True, eq=False)
class Calibration:
    """Measurements: parallel arrays of distance (m), RSSI (dBm) and line of sight."""

    distance: NDArray[np.float64]
    rssi: NDArray[np.float64]
    line_of_sight: NDArray[np.bool_]
    source: str = ""
    comments: tuple[str, ...] = ()

    def of_class(self, line_of_sight: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(distance, rssi) of the line-of-sight or the obstructed readings."""
        mask = self.line_of_sight == line_of_sight
        return self.distance[mask], self.rssi[mask]

    @property
    def synthetic(self) -> bool:
        """Whether the file's comments declare it synthetic (not measured)."""
        return any("SYNTHETIC" in c.upper() for c in self.comments)

    def means(self, line_of_sight: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Distinct distances and the mean RSSI at each (for plots and summaries)."""
        d, r = self.of_class(line_of_sight)
        distances, inverse = np.unique(d, return_inverse=True)
        sums = np.bincount(inverse, weights=r)
        counts = np.bincount(inverse)
        return distances, sums / counts


def parse_bool(text: str) -> bool | None:
    """true/false, 1/0, yes/no (any case) -> bool; anything else -> None."""
    low = text.strip().lower()
    if low in _TRUE:
        return True
    if low in _FALSE:
        return False
    return None


def load_calibration(path: str | Path, *, min_readings: int = MIN_READINGS) -> Calibration:
    """Load and validate a calibration CSV (see the module docstring)."""
    table = read_csv(path, COLUMNS)
    n = len(table.rows)
    distance = np.empty(n)
    rssi = np.empty(n)
    los = np.empty(n, dtype=bool)
    for i, (lineno, row) in enumerate(table.rows):
        distance[i] = table.number(lineno, row, "distance")
        if distance[i] < 0:
            raise table.error(lineno, "distance", f"negative distance {row['distance']}")
        rssi[i] = table.number(lineno, row, "rssi")
        flag = parse_bool(row["line_of_sight"])
        if flag is None:
            raise table.error(
                lineno,
                "line_of_sight",
                f"{row['line_of_sight']!r} is not true/false (use true, false, 1 or 0)",
            )
        los[i] = flag
    for cls, label in ((True, "line-of-sight"), (False, "obstructed")):
        count = int(np.count_nonzero(los == cls))
        if count == 0:
            raise InputError(
                f"no {label} readings (a model needs both classes)",
                file=table.path,
                field="line_of_sight",
            )
        if count < min_readings:
            raise InputError(
                f"only {count} {label} readings, need at least {min_readings}",
                file=table.path,
                field="line_of_sight",
            )
        if np.unique(distance[los == cls]).size < 2:
            raise InputError(
                f"{label} readings are all at one distance, need two or more distances",
                file=table.path,
                field="distance",
            )
    return Calibration(distance, rssi, los, str(path), table.comments)


def write_calibration(path: str | Path, calibration: Calibration, comments: Sequence[str]) -> None:
    """Write a calibration CSV (atomically) with ``#`` comment lines first."""
    rows = (
        (f"{d:g}", f"{r:g}", "true" if flag else "false")
        for d, r, flag in zip(
            calibration.distance, calibration.rssi, calibration.line_of_sight, strict=True
        )
    )
    write_csv(path, COLUMNS, rows, comments)
