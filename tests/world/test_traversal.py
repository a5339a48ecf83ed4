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
    fast_walls, fast_nearest = traversal.loops()
    for x0, y0, x1, y1 in _rays(grid, 3000, seed=1).tolist():
        ray = grid._ray(x0, y0, x1, y1)
        if ray is None:
            continue
        for gap in (1, 3):
            assert traversal.walls_loop(as_list, *ray, gap) == fast_walls(as_array, *ray, gap)
        assert traversal.nearest_loop(as_list, *ray) == fast_nearest(as_array, *ray)


def test_without_numba_the_grid_casts_the_same_rays() -> None:
    """MRCOMM_NO_NUMBA=1 (as an install without the fast extra): the plain loops, and the
    wall counts and clearances the compiled ones give."""
    grid = load_map(S4_MAP)
    rays = _rays(grid, 400, seed=2)
    here = [(grid.walls_between(*r), grid.ray_clearance(*r)) for r in rays.tolist()]
    code = (
        "import json, sys, numpy as np\n"
        "from mrcomm.world import traversal\n"
        "from mrcomm.world.mapio import load_map\n"
        f"grid = load_map({str(S4_MAP)!r})\n"
        "rays = json.loads(sys.stdin.read())\n"
        "print(traversal.KERNEL)\n"
        "print(json.dumps([(grid.walls_between(*r), grid.ray_clearance(*r)) for r in rays]))\n"
    )
    import json
    import os

    out = subprocess.run(
        [sys.executable, "-c", code], input=json.dumps(rays.tolist()), capture_output=True,
        text=True, check=True, env={**os.environ, "MRCOMM_NO_NUMBA": "1"},
    ).stdout.splitlines()  # fmt: skip
    assert out[0] == "python"
    assert [tuple(pair) for pair in json.loads(out[1])] == here
