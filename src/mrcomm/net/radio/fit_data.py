"""The data of a radio fit (:mod:`mrcomm.net.radio.fit`): RSSI readings with their
geometry, and one fitted (or kept) parameter with its interval."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
#: 95 % two-sided normal quantile.
Z95 = 1.959963984540054


@dataclass(frozen=True, eq=False)
class Readings:
    """RSSI readings and their geometry (parallel arrays, one entry per reading).

    ``tx``/``rx``: (n, 2) positions of the transmitter and the receiver (m, map frame);
    ``walls``: walls crossed by the straight line between them; ``group``: readings of
    different groups have independent shadowing (runs); ``pair`` and ``direction``: the
    unordered robot pair within the group (−1: unknown) and which way the reading went
    (±1), for the per-direction offsets; ``time``: when (s; NaN: unknown), to find the
    two directions of a pair read at the same moment."""

    tx: FloatArray
    rx: FloatArray
    rssi: FloatArray
    walls: IntArray
    group: IntArray
    pair: IntArray
    direction: IntArray
    time: FloatArray
    source: str = ""
    #: What the readings are and how they were made (printed with the fit).
    notes: tuple[str, ...] = ()

    @classmethod
    def of(
        cls,
        tx: Any,
        rx: Any,
        rssi: Any,
        walls: Any,
        *,
        group: Any = None,
        pair: Any = None,
        direction: Any = None,
        time: Any = None,
        source: str = "",
        notes: Sequence[str] = (),
    ) -> Readings:
        r = np.asarray(rssi, dtype=np.float64).reshape(-1)
        n = r.size
        return cls(
            tx=np.asarray(tx, dtype=np.float64).reshape(n, 2),
            rx=np.asarray(rx, dtype=np.float64).reshape(n, 2),
            rssi=r,
            walls=np.asarray(walls, dtype=np.int64).reshape(n),
            group=np.zeros(n, np.int64) if group is None else np.asarray(group, np.int64),
            pair=np.full(n, -1, np.int64) if pair is None else np.asarray(pair, np.int64),
            direction=(
                np.ones(n, np.int64) if direction is None else np.asarray(direction, np.int64)
            ),
            time=np.full(n, np.nan) if time is None else np.asarray(time, np.float64),
            source=source,
            notes=tuple(notes),
        )

    def __len__(self) -> int:
        return int(self.rssi.size)

    @property
    def distance(self) -> FloatArray:
        return np.asarray(np.hypot(*(self.tx - self.rx).T))

    @property
    def has_links(self) -> bool:
        """Whether the readings say which robot pair each came from."""
        return bool(self.pair.size) and bool(np.all(self.pair >= 0))

    def subset(self, mask: NDArray[np.bool_]) -> Readings:
        return Readings(
            self.tx[mask],
            self.rx[mask],
            self.rssi[mask],
            self.walls[mask],
            self.group[mask],
            self.pair[mask],
            self.direction[mask],
            self.time[mask],
            self.source,
            self.notes,
        )


@dataclass(frozen=True)
class Estimate:
    """One fitted (or kept) parameter."""

    value: float
    base: float
    #: Standard error, when the parameter was fitted freely.
    se: float | None = None
    #: 'fitted', 'kept' (the base profile's value) or 'clipped' (at a bound).
    status: str = "fitted"

    @property
    def interval(self) -> tuple[float, float] | None:
        if self.se is None:
            return None
        return (self.value - Z95 * self.se, self.value + Z95 * self.se)

    def as_dict(self) -> dict[str, Any]:
        ci = self.interval
        return {
            "value": rounded(self.value),
            "ci95": None if ci is None else [rounded(ci[0]), rounded(ci[1])],
            "se": None if self.se is None else rounded(self.se),
            "base": rounded(self.base),
            "status": self.status,
        }


def rounded(value: float, digits: int = 3) -> float:
    return float(round(float(value), digits))


# -- the fit ---------------------------------------------------------------------------
