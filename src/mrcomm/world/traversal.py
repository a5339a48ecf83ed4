"""Ray casts over an occupancy grid: the exact grid traversal (Amanatides & Woo) of a
segment, compiled when numba is there.

:class:`~mrcomm.world.occupancy.OccupancyGrid` asks these functions for a segment's
traversal (:func:`ray_setup`), the walls it crosses (:func:`walls_loop`), its clearance
(:func:`nearest_loop`), or all of that for many segments at once (:func:`cast_loop`,
what the radio's link model uses each step). They walk every cell a segment passes
through, hundreds for a long ray across a large map, which made them most of a large
team's time on the radio (S4: 17 of 36 s). With numba (the ``fast`` extra, in the
development install) the same functions are compiled to machine code; without it they
run as plain Python. The arithmetic is the same IEEE double arithmetic in the same order
either way (no fast-math), so the answers are identical (``tests/world/test_traversal.py``);
set ``MRCOMM_NO_NUMBA=1`` to use the plain functions even where numba is installed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from mrcomm.compiled import KERNEL as KERNEL  # (re-exported: which loops run)
from mrcomm.compiled import compiled

Cells = Sequence[float] | np.ndarray
#: A traversal: first flat cell index, number of cells (-1: an end off the map or on its
#: outermost cells), x step, first x crossing, x crossing interval, y step (± width),
#: first y crossing, y crossing interval. Crossings are in units of the segment (0 at its
#: start, 1 at its end); a segment parallel to an axis never crosses the other axis's
#: lines (its first crossing there is inf, so no step is ever taken that way).
Ray = tuple[int, int, int, float, float, int, float, float]


def ray_setup(
    res: float, ox: float, oy: float, width: int, height: int,
    x0: float, y0: float, x1: float, y1: float,
) -> Ray:  # fmt: skip
    """The traversal of the segment (x0, y0)–(x1, y1) over a grid of ``width`` ×
    ``height`` cells of ``res`` m whose corner is at (ox, oy)."""
    fx0, fy0 = (x0 - ox) / res, (y0 - oy) / res
    fx1, fy1 = (x1 - ox) / res, (y1 - oy) / res
    ix, iy = math.floor(fx0), math.floor(fy0)
    end_x, end_y = math.floor(fx1), math.floor(fy1)
    # Every visited cell lies in the box spanned by the two end cells (give or take one
    # cell of rounding at a tie), so bounds are checked once, here, not per cell.
    if not (0 < ix < width - 1 and 0 < end_x < width - 1 and 0 < iy < height - 1
            and 0 < end_y < height - 1):  # fmt: skip
        return 0, -1, 0, 0.0, 0.0, 0, 0.0, 0.0
    dx, dy = fx1 - fx0, fy1 - fy0
    if dx > 0:
        step_x, t_max_x, t_dx = 1, (ix + 1 - fx0) / dx, 1.0 / dx
    elif dx < 0:
        step_x, t_max_x, t_dx = -1, (fx0 - ix) / -dx, -1.0 / dx
    else:
        step_x, t_max_x, t_dx = 0, math.inf, math.inf
    if dy > 0:
        step_y, t_max_y, t_dy = width, (iy + 1 - fy0) / dy, 1.0 / dy
    elif dy < 0:
        step_y, t_max_y, t_dy = -width, (fy0 - iy) / -dy, -1.0 / dy
    else:
        step_y, t_max_y, t_dy = 0, math.inf, math.inf
    cells = abs(end_x - ix) + abs(end_y - iy) + 1
    return iy * width + ix, cells, step_x, t_max_x, t_dx, step_y, t_max_y, t_dy


def walls_loop(
    occupied: Cells, k: int, cells: int, step_x: int, t_x0: float, t_dx: float,
    step_y: int, t_y0: float, t_dy: float, gap_cells: int,
) -> int:  # fmt: skip
    """Runs of occupied cells (``occupied`` true) along the traversal, runs closer than
    ``gap_cells`` free cells counting as one.

    The n-th crossing of an x grid line is at ``t_x0 + n * t_dx``, computed from the
    count each time rather than by adding ``t_dx`` to the last one (and likewise in y).
    Added up, each next crossing waits for the addition before it, a chain of dependent
    floating-point additions the processor cannot overlap; from the count, the next
    crossing is ready as soon as the count is: S4's replayed casts take about 0.6 of
    the time (``benchmarks/bench_casts.py``; less inside a whole mission). It is also
    one rounding per crossing instead of one that accumulates: the two differ only on a
    segment through a grid corner to within about 1e-10 of a cell, where either order
    of the two crossings is the traversal's."""
    walls = 0
    free_run = gap_cells  # before the first wall: any run starts a wall
    nx = ny = 0  # grid lines crossed so far, in x and in y
    t_max_x, t_max_y = t_x0, t_y0
    for _ in range(cells):
        if occupied[k]:
            if free_run >= gap_cells:
                walls += 1
            free_run = 0
        else:
            free_run += 1
        if t_max_x < t_max_y:
            k += step_x
            nx += 1
            t_max_x = t_x0 + nx * t_dx
        else:
            k += step_y
            ny += 1
            t_max_y = t_y0 + ny * t_dy
    return walls


def nearest_loop(
    clear: Cells, k: int, cells: int, step_x: int, t_x0: float, t_dx: float,
    step_y: int, t_y0: float, t_dy: float,
) -> float:  # fmt: skip
    """The smallest clearance along the traversal, or -1 at the first occupied cell
    (crossings computed as in :func:`walls_loop`)."""
    nearest = math.inf
    nx = ny = 0
    t_max_x, t_max_y = t_x0, t_y0
    for _ in range(cells):
        c = clear[k]
        if c < nearest:
            if c == 0.0:
                return -1.0
            nearest = c
        if t_max_x < t_max_y:
            k += step_x
            nx += 1
            t_max_x = t_x0 + nx * t_dx
        else:
            k += step_y
            ny += 1
            t_max_y = t_y0 + ny * t_dy
    return nearest


def cast_loop(
    clear: Cells, occupied: Cells, res: float, ox: float, oy: float, width: int,
    height: int, segments: np.ndarray, count_walls: bool, gap_cells: int,
    walls_out: np.ndarray, clearance_out: np.ndarray,
) -> None:  # fmt: skip
    """For each segment (rows of x0, y0, x1, y1): the walls it crosses (0 in line of
    sight; 1 for any obstructed one unless ``count_walls``; 1 for an end off the map)
    and its clearance (-1 when obstructed; see OccupancyGrid.ray_clearance).

    With ``count_walls`` (the radio) most rays are obstructed (S4: 99 %): each is first
    walked over ``occupied`` for its walls, one byte a cell rather than the eight-byte
    clearances — on a large map (S4: 3.8 million cells) the long rays' reads then stay
    in the caches, which halved the casts' time — and only a ray with no wall is walked
    again over the clearances, for the nearest. Without, the walk over the clearances
    stops at the first occupied cell."""
    diagonal = math.sqrt(2.0) * res
    for i in range(segments.shape[0]):
        k, cells, step_x, t_x0, t_dx, step_y, t_y0, t_dy = _setup(
            res, ox, oy, width, height,
            segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3],
        )  # fmt: skip
        if cells < 0:
            walls_out[i] = 1
            clearance_out[i] = -1.0
            continue
        if count_walls:
            walls = _walls(occupied, k, cells, step_x, t_x0, t_dx, step_y, t_y0, t_dy, gap_cells)
            if walls > 0:
                walls_out[i] = walls
                clearance_out[i] = -1.0
                continue
        near = _nearest(clear, k, cells, step_x, t_x0, t_dx, step_y, t_y0, t_dy)
        if near >= 0.0:
            walls_out[i] = 0
            clearance_out[i] = max(0.0, near - diagonal)
        else:
            walls_out[i] = 1
            clearance_out[i] = -1.0


# What cast_loop calls: the compiled forms where numba is there, else the plain
# functions (numba resolves these globals when it compiles cast_loop).
_setup: Any = compiled(ray_setup)
_walls: Any = compiled(walls_loop)
_nearest: Any = compiled(nearest_loop)
_cast: Any = compiled(cast_loop)


def setup(*args: Any) -> Ray:
    ray: Ray = _setup(*args)
    return ray


def walls(*args: Any) -> int:
    return int(_walls(*args))


def nearest(*args: Any) -> float:
    """The smallest clearance along a traversal, or -1 when it is obstructed."""
    return float(_nearest(*args))


def cast(*args: Any) -> None:
    _cast(*args)
