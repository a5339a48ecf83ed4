"""The link model's per-pair loops (net/pair_loops.py): Python's own hypot to the last
bit, and the pair power law as it was computed pair by pair in Python."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mrcomm.net import pair_loops


def test_hypot_is_pythons_to_the_last_bit() -> None:
    """The C library's hypot differs from Python's for about one pair in 150; ours is
    CPython's algorithm (compiled or not): no difference over 300,000 pairs of
    metres to kilometres, and at the edges."""
    rng = np.random.default_rng(3)
    for low, high in ((-200.0, 200.0), (-1e-3, 1e-3), (-5e4, 5e4)):
        a, b = rng.uniform(low, high, 100_000), rng.uniform(low, high, 100_000)
        xy = np.stack([np.zeros(100_000), np.zeros(100_000)], axis=1)
        ends = np.stack([a, b], axis=1)
        out = np.empty(100_000)
        pair_loops.pair_distances(
            np.concatenate([xy, ends]), np.arange(100_000), np.arange(100_000, 200_000), out
        )
        expected = [math.hypot(-x, -y) for x, y in zip(a.tolist(), b.tolist(), strict=True)]
        assert out.tolist() == expected
    for x, y in ((0.0, 0.0), (3.0, 4.0), (-0.0, 2.5), (1e-300, 1e-300), (7.0, 0.0)):
        assert pair_loops.hypot(x, y) == math.hypot(x, y)
    assert math.isnan(pair_loops.hypot(math.nan, 1.0))
    assert pair_loops.hypot(math.inf, math.nan) == math.inf


def _power_pair_by_pair(
    distance: list[float], walls: list[int], pairs: list[tuple[int, int]], field: list[float]
) -> list[float]:
    """The law as RadioNetwork.pair_power computed it in Python, one pair at a time."""
    base, slope, wall_loss = -40.0, 10.0 * 3.1, 4.5
    scale = 1.0 / math.sqrt(2.0)
    out = []
    for k, (a, b) in enumerate(pairs):
        d = distance[k]
        if d != d:
            out.append(math.nan)
            continue
        loss = slope * math.log10(max(d, 1.0) / 1.0)
        out.append(base - loss - wall_loss * walls[k] + (field[a] + field[b]) * scale)
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_pair_power_is_the_law_pair_by_pair(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 30
    pairs = [(a, b) for a in range(n) for b in range(a + 1, n)]
    distance = rng.uniform(0.0, 80.0, len(pairs))
    distance[::17] = np.nan  # pairs with a node without a position
    walls = rng.integers(0, 4, len(pairs))
    field = rng.normal(0.0, 4.0, n)
    out = np.empty(len(pairs))
    pair_loops.pair_power(
        distance, walls, np.array([a for a, _ in pairs]), np.array([b for _, b in pairs]),
        field, -40.0, 31.0, 4.5, 1.0, out,
    )  # fmt: skip
    expected = _power_pair_by_pair(distance.tolist(), walls.tolist(), pairs, field.tolist())
    assert np.array_equal(out, np.array(expected), equal_nan=True)
