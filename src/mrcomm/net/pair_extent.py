"""The least and greatest distance each pair of nodes has had over a run.

The link recorder reports, per ordered pair, the closest and furthest its two ends came,
and per robot its closest and furthest mate. A step's distance matrix is symmetric (the
distance from a to b is the one from b to a, bit for bit: every producer fills one
triangle and mirrors it), so the least distance of (a, b) equals that of (b, a), and so
does the greatest. One (n, n) array therefore holds both: the least above the diagonal,
the greatest below it. At 10,000 robots that is 0.8 GB where two matrices held 1.6 GB.

A step updates the array a block of rows at a time, each cell once. The squares of a
block's rows and columns straddle the diagonal; their lower halves hold least distances
too (updated with the rest of the block's rows in one operation), and the greatest
distances of the pairs inside a square are kept beside, in an (n, block) array: three
array operations per block, none masked.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Rows updated or read per array operation. A team of up to this many nodes is one
#: block: a step updates two whole arrays, as fast as the two matrices did (S4's 101
#: nodes included); a larger one pays ~0.4 ms a step at 1,000 nodes for strided rows.
ROW_BLOCK = 128


class PairExtent:
    """Per unordered pair of ``n`` nodes, the least and greatest distance added so far
    (inf and 0 before any; NaN distances, a node without a position, add nothing)."""

    def __init__(self, n: int) -> None:
        self.n = n
        # Above the diagonal and in the blocks' squares the least (from inf); below the
        # diagonal outside the squares the greatest (from 0).
        self._extent = np.full((n, n), np.inf)
        for a, _ in row_blocks(n):
            self._extent[a : a + ROW_BLOCK, :a] = 0.0
        # Row i, column j - a: the greatest distance of the pair (i, j) of one block
        # starting at a.
        self._square_greatest = np.zeros((n, min(n, ROW_BLOCK)))
        # Per block: its rows, and the views of the two arrays each step updates (made
        # once: a team of one block, up to 128 nodes, then updates two whole arrays).
        self._views = [
            (
                a,
                b,
                self._extent[a:b, a:],
                self._extent[a:b, :a] if a > 0 else None,
                self._square_greatest[a:b, : b - a],
            )
            for a, b in row_blocks(n)
        ]

    def add(self, distance: FloatArray) -> None:
        """Widen every pair's extent by one step's symmetric (n, n) ``distance``."""
        whole = len(self._views) == 1
        for a, b, right, left, square in self._views:
            rows = distance if whole else distance[a:b]
            np.fmin(right, rows if whole else rows[:, a:], out=right)
            if left is not None:
                np.fmax(left, rows[:, :a], out=left)
            np.fmax(square, rows if whole else rows[:, a:b], out=square)

    def least(self, i: int, j: int) -> float:
        """The closest nodes ``i`` and ``j`` have been (inf: never both placed)."""
        return float(self._extent[min(i, j), max(i, j)]) if i != j else 0.0

    def greatest(self, i: int, j: int) -> float:
        """The furthest nodes ``i`` and ``j`` have been (0: never both placed)."""
        if i == j:
            return 0.0
        if i // ROW_BLOCK == j // ROW_BLOCK:
            return float(self._square_greatest[i, j % ROW_BLOCK])
        return float(self._extent[max(i, j), min(i, j)])

    def least_rows(self, a: int, b: int, columns: int) -> FloatArray:
        """Rows ``a:b`` of the (n, n) matrix of least distances, its first ``columns``
        columns, inf on the diagonal."""
        return self._rows(a, b, columns, upper=True, diagonal=np.inf)

    def greatest_rows(self, a: int, b: int, columns: int) -> FloatArray:
        """Rows ``a:b`` of the (n, n) matrix of greatest distances, its first
        ``columns`` columns, 0 on the diagonal."""
        rows = self._rows(a, b, columns, upper=False, diagonal=0.0)
        for first, end in row_blocks(self.n):  # the pairs inside a square: kept beside
            top, bottom, right = max(a, first), min(b, end), min(end, columns)
            if top < bottom and first < right:
                rows[top - a : bottom - a, first:right] = self._square_greatest[
                    top:bottom, : right - first
                ]
        rows[np.arange(a, b)[:, None] == np.arange(columns)[None, :]] = 0.0
        return rows

    def _rows(self, a: int, b: int, columns: int, *, upper: bool, diagonal: float) -> FloatArray:
        # Cell (i, j) of the full matrix is stored at (i, j) on its own side of the
        # diagonal and at (j, i) on the other.
        row = np.arange(a, b)[:, None]
        column = np.arange(columns)[None, :]
        own_side = column > row if upper else column < row
        rows = np.where(own_side, self._extent[a:b, :columns], self._extent[:columns, a:b].T)
        rows[row == column] = diagonal
        return rows


def row_blocks(n: int, size: int = ROW_BLOCK) -> list[tuple[int, int]]:
    """(first, end) of each block of ``size`` rows of ``n`` (the last may be shorter):
    how an (n, n) matrix is walked a bounded number of rows per array operation."""
    return [(a, min(n, a + size)) for a in range(0, n, size)]
