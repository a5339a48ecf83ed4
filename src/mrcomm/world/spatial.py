"""Which points lie near each point: a grid of square cells (spatial hashing), so that
finding every point's neighbours costs O(N) for points spread over a map instead of
checking all N² pairs."""

from __future__ import annotations

import math
from collections.abc import Sequence

Point = tuple[float, float]


def neighbours(points: Sequence[Point], radii: Sequence[float]) -> list[list[int]]:
    """For each point ``i``, the indices ``j != i``, ascending, of the points within
    ``radii[i]`` of it (distance ≤ radius)."""
    if not points:
        return []
    cell = max(max(radii), 1e-6)  # any cell at least as wide as every radius will do
    grid: dict[tuple[int, int], list[int]] = {}
    keys = []
    for j, (x, y) in enumerate(points):
        key = (math.floor(x / cell), math.floor(y / cell))
        keys.append(key)
        grid.setdefault(key, []).append(j)
    out: list[list[int]] = []
    for i, (x, y) in enumerate(points):
        cx, cy = keys[i]
        r2 = radii[i] * radii[i]
        near = []
        # Every radius is at most one cell: the 3 x 3 block around the point holds
        # every point within it.
        for gx in (cx - 1, cx, cx + 1):
            for gy in (cy - 1, cy, cy + 1):
                for j in grid.get((gx, gy), ()):
                    if j != i:
                        ox, oy = points[j]
                        if (ox - x) * (ox - x) + (oy - y) * (oy - y) <= r2:
                            near.append(j)
        near.sort()
        out.append(near)
    return out
