"""The inner loops of a ray cast over an occupancy grid, compiled when numba is there.

:class:`~mrcomm.world.occupancy.OccupancyGrid` sets up an exact grid traversal
(Amanatides & Woo) of a segment and hands its parameters to one of these loops: one
counts the walls the segment crosses, the other finds the clearance along it. They walk
every cell the segment passes through, hundreds for a long ray across a large map,
which made them most of a large team's time on the radio (S4: 17 of 36 s). With numba
(the ``fast`` extra, in the development install) the same functions are compiled to
machine code; without it they run as plain Python. The arithmetic is the same IEEE
double arithmetic in the same order either way (no fast-math), so the answers are
identical (``tests/world/test_traversal.py``); set ``MRCOMM_NO_NUMBA=1`` to use the plain
Python loops even where numba is installed.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

Cells = Sequence[float] | np.ndarray


def walls_loop(
    clear: Cells, k: int, cells: int, step_x: int, t_max_x: float, t_dx: float,
    step_y: int, t_max_y: float, t_dy: float, gap_cells: int,
) -> int:  # fmt: skip
    """Runs of occupied cells (clearance 0) along the traversal, runs closer than
    ``gap_cells`` free cells counting as one."""
    walls = 0
    free_run = gap_cells  # before the first wall: any run starts a wall
    for _ in range(cells):
        if clear[k] == 0.0:
            if free_run >= gap_cells:
                walls += 1
            free_run = 0
        else:
            free_run += 1
        if t_max_x < t_max_y:
            k += step_x
            t_max_x += t_dx
        else:
            k += step_y
            t_max_y += t_dy
    return walls


def nearest_loop(
    clear: Cells, k: int, cells: int, step_x: int, t_max_x: float, t_dx: float,
    step_y: int, t_max_y: float, t_dy: float,
) -> float:  # fmt: skip
    """The smallest clearance along the traversal, or -1 at the first occupied cell."""
    nearest = np.inf
    for _ in range(cells):
        c = clear[k]
        if c < nearest:
            if c == 0.0:
                return -1.0
            nearest = c
        if t_max_x < t_max_y:
            k += step_x
            t_max_x += t_dx
        else:
            k += step_y
            t_max_y += t_dy
    return float(nearest)


def _compiled() -> tuple[Callable[..., int], Callable[..., float]] | None:
    if os.environ.get("MRCOMM_NO_NUMBA"):
        return None
    try:
        import numba  # type: ignore[import-untyped,unused-ignore]
    except ImportError:
        return None
    jit: Any = numba.njit(cache=True, nogil=True)
    return jit(walls_loop), jit(nearest_loop)


_FAST = _compiled()
#: Which loops ray casts use: "numba" or "python".
KERNEL = "python" if _FAST is None else "numba"


def loops() -> tuple[Callable[..., int], Callable[..., float]]:
    """(walls, nearest): the compiled loops where numba is there, else the plain ones."""
    return _FAST if _FAST is not None else (walls_loop, nearest_loop)
