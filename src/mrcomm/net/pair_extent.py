"""The least and greatest distance each pair of nodes has had over a run, in one array.

The link recorder reports, per ordered pair, the closest and furthest its two ends came,
and per robot its closest and furthest mate. A step's distance matrix is symmetric (the
distance from a to b is the one from b to a, bit for bit: every producer fills one
triangle and mirrors it), so the least distance of (a, b) equals that of (b, a), and so
does the greatest. One (n, n) array therefore holds both: the least above the diagonal,
the greatest below it. At 10,000 robots that is 0.8 GB where two matrices held 1.6 GB,
and a step updates each cell once where two matrices updated every cell twice.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Rows updated or read per array operation: a block's scratch is this many rows of the
#: team, whatever its size.
ROW_BLOCK = 64


class PairExtent:
    """Per unordered pair of ``n`` nodes, the least and greatest distance added so far
    (inf and 0 before any; NaN distances, a node without a position, add nothing)."""

    def __init__(self, n: int) -> None:
        self.n = n
        # Above the diagonal the least (from inf), below it the greatest (from 0).
        self._extent = np.full((n, n), np.inf)
        for a, b in row_blocks(n):
            self._extent[a:b, :a] = 0.0
            self._extent[a:b, a:b][~_UPPER[: b - a, : b - a]] = 0.0
        self._dirty = False

    def add(self, distance: FloatArray) -> None:
        """Widen every pair's extent by one step's symmetric (n, n) ``distance``."""
        extent = self._extent
        n = self.n
        for a, b in row_blocks(n):
            if b < n:  # right of the block's square: above the diagonal
                np.fmin(extent[a:b, b:], distance[a:b, b:], out=extent[a:b, b:])
            if a > 0:  # left of it: below the diagonal
                np.fmax(extent[a:b, :a], distance[a:b, :a], out=extent[a:b, :a])
            square, step = extent[a:b, a:b], distance[a:b, a:b]
            least = np.fmin(square, step)
            np.fmax(square, step, out=square)
            np.copyto(square, least, where=_UPPER[: b - a, : b - a])

    def least(self, i: int, j: int) -> float:
        """The closest nodes ``i`` and ``j`` have been (inf: never both placed)."""
        return float(self._extent[min(i, j), max(i, j)]) if i != j else 0.0

    def greatest(self, i: int, j: int) -> float:
        """The furthest nodes ``i`` and ``j`` have been (0: never both placed)."""
        return float(self._extent[max(i, j), min(i, j)]) if i != j else 0.0

    def least_rows(self, a: int, b: int, columns: int) -> FloatArray:
        """Rows ``a:b`` of the (n, n) matrix of least distances, its first ``columns``
        columns, inf on the diagonal."""
        return self._rows(a, b, columns, upper=True, diagonal=np.inf)

    def greatest_rows(self, a: int, b: int, columns: int) -> FloatArray:
        """Rows ``a:b`` of the (n, n) matrix of greatest distances, its first
        ``columns`` columns, 0 on the diagonal."""
        return self._rows(a, b, columns, upper=False, diagonal=0.0)

    def _rows(self, a: int, b: int, columns: int, *, upper: bool, diagonal: float) -> FloatArray:
        # Cell (i, j) of the full matrix is stored at (i, j) on its own side of the
        # diagonal and at (j, i) on the other.
        row = np.arange(a, b)[:, None]
        column = np.arange(columns)[None, :]
        own_side = column > row if upper else column < row
        rows = np.where(own_side, self._extent[a:b, :columns], self._extent[:columns, a:b].T)
        rows[row == column] = diagonal
        return rows


def row_blocks(n: int) -> list[tuple[int, int]]:
    """(first, end) of each block of :data:`ROW_BLOCK` rows of ``n``."""
    return [(a, min(n, a + ROW_BLOCK)) for a in range(0, n, ROW_BLOCK)]


#: Within a block's square on the diagonal, the cells above the diagonal.
_UPPER = np.triu(np.ones((ROW_BLOCK, ROW_BLOCK), dtype=np.bool_), k=1)
