"""One array of least and greatest pair distances equals the two matrices it replaces."""

from __future__ import annotations

import numpy as np
import pytest

from mrcomm.net.links import distance_matrix
from mrcomm.net.pair_extent import ROW_BLOCK, PairExtent, row_blocks


@pytest.mark.parametrize("n", [0, 1, 2, 5, ROW_BLOCK, ROW_BLOCK + 1, 2 * ROW_BLOCK + 7])
def test_extent_equals_a_least_and_a_greatest_matrix(n: int) -> None:
    rng = np.random.default_rng(n)
    extent = PairExtent(n)
    least, greatest = np.full((n, n), np.inf), np.zeros((n, n))
    for step in range(6):
        at = rng.uniform(-50.0, 50.0, size=(n, 2))
        if n > 2 and step % 2:
            at[rng.integers(n)] = np.nan  # a node without a position this step
        distance = distance_matrix(at)
        extent.add(distance)
        np.fmin(least, distance, out=least)
        np.fmax(greatest, distance, out=greatest)
    off = ~np.eye(n, dtype=np.bool_)
    for i in range(n):
        for j in range(n):
            if i != j:
                assert extent.least(i, j) == least[i, j]
                assert extent.greatest(i, j) == greatest[i, j]
    for columns in (n, max(0, n - 3)):
        rows_least = extent.least_rows(0, n, columns)
        rows_greatest = extent.greatest_rows(0, n, columns)
        assert np.array_equal(rows_least, np.where(off, least, np.inf)[:, :columns])
        assert np.array_equal(rows_greatest, np.where(off, greatest, 0.0)[:, :columns])
        for a, b in row_blocks(n):  # as the recorder reads them: a block at a time
            assert np.array_equal(extent.least_rows(a, b, columns), rows_least[a:b])
            assert np.array_equal(extent.greatest_rows(a, b, columns), rows_greatest[a:b])


def test_an_unplaced_pair_has_no_extent() -> None:
    extent = PairExtent(3)
    at = np.array([[0.0, 0.0], [3.0, 4.0], [np.nan, np.nan]])
    extent.add(distance_matrix(at))
    assert extent.least(0, 1) == extent.greatest(1, 0) == 5.0
    assert extent.least(0, 2) == np.inf and extent.greatest(2, 0) == 0.0
