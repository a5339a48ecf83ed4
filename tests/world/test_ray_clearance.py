"""ray_clearance: the same visibility as line_of_sight, and a clearance bound that
holds, so the link model may skip re-casting rays whose ends moved less than it."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from mrcomm.world.mapio import load_map
from tests.conftest import ROOT


def test_visibility_matches_and_the_bound_is_safe() -> None:
    grid = load_map(ROOT / "data" / "maps" / "office.yaml")
    rng = np.random.default_rng(5)
    free = np.argwhere(~grid.inflated(0.18).occupied)
    occupied = np.argwhere(grid.occupied)
    res = grid.resolution
    centres = np.column_stack(
        [
            occupied[:, 1] * res + res / 2 + grid.origin[0],
            occupied[:, 0] * res + res / 2 + grid.origin[1],
        ]
    )
    tree = cKDTree(centres)
    checked = visible = 0
    while checked < 400:
        a = grid.cell_to_world(*free[rng.integers(len(free))])
        b = grid.cell_to_world(*free[rng.integers(len(free))])
        if math.hypot(a[0] - b[0], a[1] - b[1]) > 8.0:
            continue
        checked += 1
        clearance = grid.ray_clearance(*a, *b)
        assert (clearance >= 0.0) == grid.line_of_sight(*a, *b)
        if clearance > 0.0:
            visible += 1
            points = np.array(a) + np.outer(np.linspace(0, 1, 300), np.subtract(b, a))
            true = tree.query(points)[0].min() - res * math.sqrt(2) / 2  # to cell edges
            assert clearance <= true + 1e-9
    assert visible > 50  # the sample exercised the bound
