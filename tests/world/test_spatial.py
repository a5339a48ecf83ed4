"""The grid of cells finds exactly the points within each radius (against all pairs)."""

from __future__ import annotations

import math

import numpy as np

from mrcomm.world.spatial import MATRIX_UP_TO, _by_grid, _by_matrix, neighbours


def brute(points: list[tuple[float, float]], radii: list[float]) -> list[list[int]]:
    return [
        [
            j
            for j, q in enumerate(points)
            if j != i and (q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2 <= radii[i] ** 2
        ]
        for i, p in enumerate(points)
    ]


def test_same_as_all_pairs_on_random_teams() -> None:
    rng = np.random.default_rng(7)
    for n, side in ((1, 5.0), (12, 4.0), (200, 60.0), (500, 30.0)):
        xy = rng.uniform(-side, side, size=(n, 2))
        points = [(float(x), float(y)) for x, y in xy]
        radii = rng.uniform(0.5, 4.5, size=n).tolist()
        assert neighbours(points, radii) == brute(points, radii)


def test_boundary_and_cell_edges() -> None:
    # Exactly at the radius counts; points on cell edges and at negative coordinates.
    points = [(0.0, 0.0), (3.0, 0.0), (-3.0, 0.0), (0.0, -3.0000001), (3.0, 3.0)]
    got = neighbours(points, [3.0] * len(points))
    assert got == brute(points, [3.0] * len(points))
    assert got[0] == [1, 2]
    assert math.hypot(3.0, 3.0) > 3.0 and 4 not in got[0]


def test_empty_and_zero_radius() -> None:
    assert neighbours([], []) == []
    assert neighbours([(0.0, 0.0), (0.0, 0.0), (1.0, 0.0)], [0.0] * 3) == [[1], [0], []]


def test_matrix_and_grid_give_the_same_answers() -> None:
    # Small teams take all pairs at once, large ones the grid: the same neighbours, in
    # the same order, down to points exactly at the radius.
    rng = np.random.default_rng(11)
    for n in (2, 30, MATRIX_UP_TO, MATRIX_UP_TO + 1):
        xy = np.round(rng.uniform(-20.0, 20.0, size=(n, 2)), 1)  # many exact ties
        points = [(float(x), float(y)) for x, y in xy]
        radii = rng.choice([0.0, 1.0, 2.5, 3.0], size=n).tolist()
        assert _by_matrix(points, radii) == _by_grid(points, radii) == brute(points, radii)
