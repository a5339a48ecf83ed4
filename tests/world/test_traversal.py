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
