"""The ray-cast loops (world/traversal.py): compiled with numba and as plain Python,
the same answers on every ray; the plain loops are what runs without numba."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mrcomm.world import traversal
from mrcomm.world.mapio import load_map

S4_MAP = Path(__file__).resolve().parents[2] / "data" / "scenarios" / "s4" / "s4_map.yaml"


def _cast_ray(grid, x0: float, y0: float, x1: float, y1: float, count: bool) -> tuple[int, float]:  # type: ignore[no-untyped-def]
    clearance = grid.ray_clearance(x0, y0, x1, y1)
    if clearance >= 0.0:
        return 0, clearance
    return (grid.walls_between(x0, y0, x1, y1) if count else 1), -1.0


def _rays(grid, n: int, seed: int) -> np.ndarray:  # type: ignore[no-untyped-def]
    x0, x1, y0, y1 = grid.extent
    rng = np.random.default_rng(seed)
    return rng.uniform([x0, y0, x0, y0], [x1, y1, x1, y1], size=(n, 4))


def test_compiled_and_plain_loops_agree_on_every_ray() -> None:
    if traversal.KERNEL != "numba":
        pytest.skip("numba is not installed (pip install mrcomm[fast]): nothing to compare")
    grid = load_map(S4_MAP)
    field = grid.distance_field().ravel()
    as_list, as_array = field.tolist(), np.ascontiguousarray(field)
    occupied = grid.occupied.ravel()
    occupied_list, occupied_array = occupied.tolist(), np.ascontiguousarray(occupied)
    height, width = grid.occupied.shape
    ox, oy = grid.origin
    shape = (grid.resolution, ox, oy, width, height)
    rays = _rays(grid, 3000, seed=1)
    for x0, y0, x1, y1 in rays.tolist():
        ray = traversal.ray_setup(*shape, x0, y0, x1, y1)
        assert ray == traversal.setup(*shape, x0, y0, x1, y1)
        if ray[1] < 0:
            continue
        for gap in (1, 3):
            assert traversal.walls_loop(occupied_list, *ray, gap) == traversal.walls(
                occupied_array, *ray, gap
            )
        assert traversal.nearest_loop(as_list, *ray) == traversal.nearest(as_array, *ray)
    # Many at once, compiled, against one at a time through the grid.
    for count in (True, False):
        walls, clearance = grid.cast_many(rays, count)
        one_by_one = [_cast_ray(grid, *r, count) for r in rays.tolist()]
        assert list(zip(walls.tolist(), clearance.tolist(), strict=True)) == one_by_one


def test_without_numba_the_grid_casts_the_same_rays() -> None:
    """MRCOMM_NO_NUMBA=1 (as an install without the fast extra): the plain loops, and the
    wall counts and clearances the compiled ones give."""
    grid = load_map(S4_MAP)
    rays = _rays(grid, 400, seed=2)
    walls, clearance = grid.cast_many(rays, True)
    here = [(grid.walls_between(*r), grid.ray_clearance(*r)) for r in rays.tolist()]
    assert walls.tolist() == [w if c < 0 else 0 for w, c in here]
    assert clearance.tolist() == [c for _, c in here]
    code = (
        "import json, sys, numpy as np\n"
        "from mrcomm.world import traversal\n"
        "from mrcomm.world.mapio import load_map\n"
        f"grid = load_map({str(S4_MAP)!r})\n"
        "rays = json.loads(sys.stdin.read())\n"
        "print(traversal.KERNEL)\n"
        "print(json.dumps([(grid.walls_between(*r), grid.ray_clearance(*r)) for r in rays]))\n"
        "w, c = grid.cast_many(np.array(rays), True)\n"
        "print(json.dumps([w.tolist(), c.tolist()]))\n"
    )
    import json
    import os

    out = subprocess.run(
        [sys.executable, "-c", code], input=json.dumps(rays.tolist()), capture_output=True,
        text=True, check=True, env={**os.environ, "MRCOMM_NO_NUMBA": "1"},
    ).stdout.splitlines()  # fmt: skip
    assert out[0] == "python"
    assert [tuple(pair) for pair in json.loads(out[1])] == here
    assert json.loads(out[2]) == [walls.tolist(), clearance.tolist()]


def _exact_cells(x0: float, y0: float, x1: float, y1: float, width: int) -> list[int]:
    """The cells a segment passes through (grid of 1 m cells at the origin), in order,
    by exact rational arithmetic on the same end points: the n-th x crossing is at
    (ix + 1 + n - x0) / dx exactly; at a tie (a grid corner) the y step comes first, as
    in the loops."""
    from fractions import Fraction

    fx0, fy0, fx1, fy1 = (Fraction(v) for v in (x0, y0, x1, y1))
    ix, iy = int(np.floor(x0)), int(np.floor(y0))
    cells = abs(int(np.floor(x1)) - ix) + abs(int(np.floor(y1)) - iy) + 1
    dx, dy = fx1 - fx0, fy1 - fy0
    sx, sy = (dx > 0) - (dx < 0), (dy > 0) - (dy < 0)

    def crossing(start: int, origin: Fraction, d: Fraction, step: int, n: int) -> Fraction | None:
        if step == 0:
            return None  # parallel: never crosses
        line = start + 1 + n if step > 0 else start - n
        return (line - origin) / d

    visited, nx, ny = [], 0, 0
    for _ in range(cells):
        visited.append((iy + sy * ny) * width + ix + sx * nx)
        tx = crossing(ix, fx0, dx, sx, nx)
        ty = crossing(iy, fy0, dy, sy, ny)
        if tx is not None and (ty is None or tx < ty):
            nx += 1
        else:
            ny += 1
    return visited


def test_the_loops_walk_exactly_the_cells_the_segment_passes_through() -> None:
    """Against exact arithmetic: on random grids and segments, and on segments through
    grid corners and along grid lines (ties and parallel cases), the wall counts and
    clearances are those of the cells the segment really passes through."""
    rng = np.random.default_rng(7)
    width = height = 40
    rays = rng.uniform(1.0, 39.0, size=(400, 4)).tolist()
    # Through corners (diagonals from cell centres), along a row, along a column.
    rays += [[1.5, 1.5, 30.5, 30.5], [30.5, 2.5, 2.5, 30.5], [1.2, 5.5, 38.7, 5.5],
             [7.5, 38.2, 7.5, 1.1], [2.0, 2.0, 20.0, 11.0], [3.25, 3.75, 3.25, 3.75]]  # fmt: skip
    for density in (0.02, 0.2):
        occupied = rng.random((height, width)) < density
        flat = occupied.ravel()
        clear = rng.uniform(0.1, 5.0, size=flat.size)
        clear[flat] = 0.0
        for x0, y0, x1, y1 in rays:
            ray = traversal.ray_setup(1.0, 0.0, 0.0, width, height, x0, y0, x1, y1)
            cells = _exact_cells(x0, y0, x1, y1, width)
            assert ray[1] == len(cells)
            for gap in (1, 3):
                want, run = 0, gap
                for k in cells:
                    if flat[k]:
                        want += run >= gap
                        run = 0
                    else:
                        run += 1
                assert traversal.walls_loop(flat.tolist(), *ray, gap) == want
                assert traversal.walls(np.ascontiguousarray(flat), *ray, gap) == want
            nearest = -1.0 if flat[cells].any() else float(clear[cells].min())
            assert traversal.nearest_loop(clear.tolist(), *ray) == nearest
            assert traversal.nearest(np.ascontiguousarray(clear), *ray) == nearest
