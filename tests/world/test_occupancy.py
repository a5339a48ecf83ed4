"""Occupancy grid: inflation and line of sight."""

from __future__ import annotations

import numpy as np
import pytest

from mrcomm.world.occupancy import OccupancyGrid


def _empty(h: int = 41, w: int = 41, res: float = 0.05) -> OccupancyGrid:
    return OccupancyGrid(np.zeros((h, w), dtype=np.bool_), res, (-1.0, -1.0))


@pytest.mark.parametrize("radius", [0.0, 0.05, 0.18, 0.2, 0.33])
def test_single_obstacle_inflates_to_exactly_the_cells_within_radius(radius: float) -> None:
    grid = _empty()
    occ = grid.occupied.copy()
    occ[20, 20] = True
    grid = OccupancyGrid(occ, grid.resolution, grid.origin)
    inflated = grid.inflated(radius).occupied
    iy, ix = np.indices(occ.shape)
    within = np.hypot(iy - 20, ix - 20) * grid.resolution <= radius
    np.testing.assert_array_equal(inflated, within)
    assert not grid.occupied[19, 20]  # the original is left alone


def test_inflation_of_a_wall_narrows_a_door() -> None:
    occ = np.zeros((20, 40), dtype=np.bool_)
    occ[10, :] = True
    occ[10, 12:28] = False  # a 16-cell (0.8 m) door
    grid = OccupancyGrid(occ, 0.05)
    door_row = grid.inflated(0.2).occupied[10]
    assert int((~door_row).sum()) == 8  # 0.4 m of free centre line


def _walled() -> OccupancyGrid:
    occ = np.zeros((40, 60), dtype=np.bool_)
    occ[:, 30] = True  # a vertical wall, one cell thick, at x in [1.5, 1.55)
    occ[0:5, 30] = False  # with a gap at the bottom
    return OccupancyGrid(occ, 0.05)


def test_line_of_sight_through_wall_is_blocked() -> None:
    grid = _walled()
    assert not grid.line_of_sight(0.5, 1.0, 2.5, 1.0)
    assert not grid.line_of_sight(0.5, 1.9, 2.5, 0.3)  # oblique through the thin wall


def test_line_of_sight_in_free_space() -> None:
    grid = _walled()
    assert grid.line_of_sight(0.2, 0.2, 1.4, 1.9)
    assert grid.line_of_sight(0.5, 0.1, 2.5, 0.1)  # through the gap
    assert grid.line_of_sight(1.0, 1.0, 1.0, 1.0)  # a point


def test_line_of_sight_off_map_is_blocked() -> None:
    grid = _walled()
    assert not grid.line_of_sight(0.5, 0.5, -0.5, 0.5)
    assert not grid.line_of_sight_many(np.array([[5.0, 5.0]]), np.array([[0.5, 0.5]]))[0]


def test_vectorised_matches_scalar_on_random_segments() -> None:
    rng = np.random.default_rng(12345)
    occ = rng.random((60, 80)) < 0.03
    grid = OccupancyGrid(occ, 0.05, (0.5, -0.25))
    xmin, xmax, ymin, ymax = grid.extent
    n = 400
    # Lengths from a few cells to the whole map, so batch and segment lengths differ.
    starts = np.column_stack([rng.uniform(xmin, xmax, n), rng.uniform(ymin, ymax, n)])
    ends = starts + rng.normal(0.0, rng.choice([0.1, 1.0, 3.0], n)[:, None], (n, 2))
    many = grid.line_of_sight_many(starts, ends)
    scalar = np.array([grid.line_of_sight(*s, *e) for s, e in zip(starts, ends, strict=True)])
    np.testing.assert_array_equal(many, scalar)
    assert 0 < many.sum() < n  # both outcomes occur, so the comparison means something


def test_line_of_sight_empty_batch() -> None:
    grid = _walled()
    assert grid.line_of_sight_many(np.zeros((0, 2)), np.zeros((0, 2))).shape == (0,)


def test_ends_on_the_outermost_cells_are_obstructed() -> None:
    # Bounds are checked once at the ends (not per cell): a ray may touch the map's
    # border only by ending there, and that counts as obstructed, as off the map does.
    grid = _empty()  # 41 x 41 cells of 5 cm from (-1, -1); no obstacle at all
    assert grid.line_of_sight(-0.9, 0.0, 0.9, 0.0)  # second cell to second-last cell
    assert not grid.line_of_sight(-0.99, 0.0, 0.9, 0.0)  # starts on the first column
    assert not grid.line_of_sight(0.0, 0.0, 0.0, 1.04)  # ends on the last row
    assert grid.ray_clearance(-0.99, 0.0, 0.9, 0.0) < 0.0


def test_ray_clearance_is_the_nearest_wall_along_the_ray_less_a_cell_diagonal() -> None:
    grid = _walled()  # wall at x in [1.5, 1.55), open below y = 0.25
    # A horizontal ray at y = 1.025 from x = 0.525 to 1.025: nearest wall cell centre
    # 1.525 - 1.025 = 0.5 m from the ray's last cell centre.
    clearance = grid.ray_clearance(0.525, 1.025, 1.025, 1.025)
    assert clearance == pytest.approx(0.5 - np.sqrt(2) * 0.05)
