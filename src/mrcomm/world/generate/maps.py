"""Floor plans drawn for any size: each kind a pure function of (width, height,
resolution, random generator) to an occupancy array (``True``: occupied; row 0 at the
map's origin, as :class:`~mrcomm.world.occupancy.OccupancyGrid` holds it).

* ``office`` — corridors 2 m wide every ~11 m, rooms of 4-6 m on both sides, each with
  a 0.9 m door onto its corridor (like the reference office floor), a spine corridor
  joining them;
* ``warehouse`` — shelf rows 1.2 m deep and 2.6 m aisles, a 4 m cross aisle and a 6 m
  loading area along the south wall;
* ``campus`` — open ground fenced in, with buildings of 12-30 m (0.3 m walls), each with
  two 1.2 m doors and an inner wall with a door;
* ``grid`` — open floor with 0.6 m pillars every 3 m;
* ``corridor`` — two halls at either end (up to 8 m deep, the map's full height) joined
  by a one-lane corridor 1 m wide: robots crossing it both ways must queue.

Every plan is enclosed by a 0.3 m outer wall. Random choices come only from ``rng``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

Occupancy = NDArray[np.bool_]
WALL = 0.3  # m, thickness of every wall
DOOR = 0.9  # m, an office door (the robots are 0.36 m wide)
ROOM_MIN = 2.5  # m, the narrowest office room (its door 0.6 m from either wall)


class Plan:
    """An occupancy array drawn in metres."""

    def __init__(self, width: float, height: float, resolution: float) -> None:
        self.resolution = resolution
        self.width = width
        self.height = height
        ny, nx = round(height / resolution), round(width / resolution)
        self.cells = np.zeros((ny, nx), dtype=np.bool_)

    def _index(self, value: float, size: int) -> int:
        return min(max(round(value / self.resolution), 0), size)

    def fill(self, x0: float, y0: float, x1: float, y1: float, occupied: bool = True) -> None:
        """Set the rectangle [x0, x1] x [y0, y1] (metres, any order)."""
        ny, nx = self.cells.shape
        ix0, ix1 = sorted((self._index(x0, nx), self._index(x1, nx)))
        iy0, iy1 = sorted((self._index(y0, ny), self._index(y1, ny)))
        self.cells[iy0:iy1, ix0:ix1] = occupied

    def wall_x(self, x0: float, x1: float, y: float) -> None:
        """A horizontal wall along y from x0 to x1."""
        self.fill(x0, y - WALL / 2, x1, y + WALL / 2)

    def wall_y(self, x: float, y0: float, y1: float) -> None:
        """A vertical wall along x from y0 to y1."""
        self.fill(x - WALL / 2, y0, x + WALL / 2, y1)

    def enclose(self) -> None:
        self.fill(0, 0, self.width, WALL)
        self.fill(0, self.height - WALL, self.width, self.height)
        self.fill(0, 0, WALL, self.height)
        self.fill(self.width - WALL, 0, self.width, self.height)


def office(width: float, height: float, resolution: float, rng: np.random.Generator) -> Occupancy:
    plan = Plan(width, height, resolution)
    plan.fill(0, 0, width, height)  # solid, rooms and corridors carved out
    corridor = 2.0
    band = 11.0  # a corridor with a row of rooms on each side
    spine_lo, spine_hi = width / 2 - corridor / 2, width / 2 + corridor / 2
    plan.fill(spine_lo, WALL, spine_hi, height - WALL, False)
    y = WALL
    while y + 4.0 <= height - WALL:
        top = min(y + band, height - WALL)
        mid = (y + top) / 2
        # The corridor of this band, wall to wall.
        plan.fill(WALL, mid - corridor / 2, width - WALL, mid + corridor / 2, False)
        for south in (True, False):
            lo, hi = (y + WALL / 2, mid - corridor / 2) if south else (mid + corridor / 2, top)
            if hi - lo < 2.0:
                continue
            x = WALL
            while x < width - WALL - ROOM_MIN:
                right = min(x + float(rng.uniform(4.0, 6.0)), width - WALL)
                if x < spine_hi and right > spine_lo:  # rooms stop at the spine corridor
                    if spine_lo - x < ROOM_MIN:
                        x = spine_hi
                        continue
                    right = spine_lo
                if right - x < ROOM_MIN:
                    break
                plan.fill(x + WALL / 2, lo + WALL / 2, right - WALL / 2, hi - WALL / 2, False)
                door = float(rng.uniform(x + 0.6, right - 0.6 - DOOR))
                edge = hi if south else lo
                plan.fill(door, edge - WALL, door + DOOR, edge + WALL, False)
                x = right
        y = top
    plan.enclose()
    return plan.cells


def warehouse(
    width: float, height: float, resolution: float, rng: np.random.Generator
) -> Occupancy:
    plan = Plan(width, height, resolution)
    loading = 6.0
    depth, aisle, cross = 1.2, 2.6, 4.0
    shelf = float(rng.uniform(7.0, 10.0))  # length of one shelf block
    cross_lo, cross_hi = width / 2 - cross / 2, width / 2 + cross / 2
    y = loading
    while y + 2 * depth + aisle <= height - 1.5:
        # A double row (back to back) of blocks with 2 m gaps, then an aisle.
        x = 2.0
        while x + 1.0 <= width - 2.0:
            end = min(x + shelf, width - 2.0)
            if x < cross_hi and end > cross_lo:  # blocks stop at the cross aisle
                if cross_lo - x >= 1.0:
                    plan.fill(x, y, cross_lo, y + 2 * depth)
                x = cross_hi
                continue
            plan.fill(x, y, end, y + 2 * depth)
            x = end + 2.0
        y += 2 * depth + aisle
    plan.enclose()
    return plan.cells


def campus(width: float, height: float, resolution: float, rng: np.random.Generator) -> Occupancy:
    plan = Plan(width, height, resolution)
    placed: list[tuple[float, float, float, float]] = []
    tries = 0
    target = max(1, int(width * height / 900))  # about one building per 30 x 30 m
    while len(placed) < target and tries < 50 * target:
        tries += 1
        w, h = float(rng.uniform(12, 30)), float(rng.uniform(12, 30))
        x0 = float(rng.uniform(4, max(4.0, width - w - 4)))
        y0 = float(rng.uniform(4, max(4.0, height - h - 4)))
        if x0 + w > width - 4 or y0 + h > height - 4:
            continue
        if any(x0 < b[2] + 6 and b[0] < x0 + w + 6 and y0 < b[3] + 6 and b[1] < y0 + h + 6
               for b in placed):  # fmt: skip
            continue  # keep 6 m of open ground (a path) between buildings
        placed.append((x0, y0, x0 + w, y0 + h))
        plan.wall_x(x0, x0 + w, y0)
        plan.wall_x(x0, x0 + w, y0 + h)
        plan.wall_y(x0, y0, y0 + h)
        plan.wall_y(x0 + w, y0, y0 + h)
        door = 1.2
        south = float(rng.uniform(x0 + 1, x0 + w - 1 - door))
        plan.fill(south, y0 - WALL, south + door, y0 + WALL, False)
        north = float(rng.uniform(x0 + 1, x0 + w - 1 - door))
        plan.fill(north, y0 + h - WALL, north + door, y0 + h + WALL, False)
        inner = x0 + w / 2  # an inner wall with a door splits the building
        plan.wall_y(inner, y0, y0 + h)
        gap = float(rng.uniform(y0 + 1, y0 + h - 1 - DOOR))
        plan.fill(inner - WALL, gap, inner + WALL, gap + DOOR, False)
    plan.enclose()
    return plan.cells


def grid(width: float, height: float, resolution: float, rng: np.random.Generator) -> Occupancy:
    plan = Plan(width, height, resolution)
    pitch, side = 3.0, 0.6
    offset = float(rng.uniform(1.5, 2.5))
    x = offset
    while x + side < width - 1.0:
        y = offset
        while y + side < height - 1.0:
            plan.fill(x, y, x + side, y + side)
            y += pitch
        x += pitch
    plan.enclose()
    return plan.cells


def corridor(width: float, height: float, resolution: float, rng: np.random.Generator) -> Occupancy:
    plan = Plan(width, height, resolution)
    plan.fill(0, 0, width, height)
    hall = min(8.0, (width - 2 * WALL) / 3)
    plan.fill(WALL, WALL, WALL + hall, height - WALL, False)
    plan.fill(width - WALL - hall, WALL, width - WALL, height - WALL, False)
    lane = 1.0
    plan.fill(WALL + hall, height / 2 - lane / 2, width - WALL - hall, height / 2 + lane / 2, False)
    return plan.cells


#: Map kinds ``mrcomm scenario make --map`` draws, with their smallest side (m).
KINDS: dict[str, tuple[Callable[..., Occupancy], float]] = {
    "office": (office, 12.0),
    "warehouse": (warehouse, 16.0),
    "campus": (campus, 30.0),
    "grid": (grid, 8.0),
    "corridor": (corridor, 6.0),
}
