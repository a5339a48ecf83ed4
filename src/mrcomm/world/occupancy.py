"""Occupancy grid: the map as a boolean array, world/cell conversion, inflation and
line-of-sight ray casting.

Convention: ``occupied[iy, ix]`` with ``iy = 0`` the row at the map origin (the bottom of
the ROS map image; map IO flips rows). Cell ``(iy, ix)`` covers
``[origin_x + ix*res, origin_x + (ix+1)*res) x [origin_y + iy*res, ...)``.
Unknown cells of a ROS map count as occupied.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrcomm.world import traversal


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A static occupancy grid in the map frame."""

    occupied: NDArray[np.bool_]
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)
    _free_distance: NDArray[np.float64] | None = field(default=None, repr=False, compare=False)
    _clearance_list: Any = field(default=None, repr=False, compare=False)
    _occupied_list: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.occupied.ndim != 2 or self.occupied.dtype != np.bool_:
            raise ValueError("occupied must be a 2-D boolean array")
        if not self.resolution > 0:
            raise ValueError("resolution must be positive")

    @property
    def height(self) -> int:
        return int(self.occupied.shape[0])

    @property
    def width(self) -> int:
        return int(self.occupied.shape[1])

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax) in metres, for plotting."""
        ox, oy = self.origin
        return (ox, ox + self.width * self.resolution, oy, oy + self.height * self.resolution)

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """(iy, ix) of the cell holding a world point (may be outside the grid)."""
        ox, oy = self.origin
        return int(np.floor((y - oy) / self.resolution)), int(np.floor((x - ox) / self.resolution))

    def cell_to_world(self, iy: int, ix: int) -> tuple[float, float]:
        """World coordinates of a cell centre."""
        ox, oy = self.origin
        return ox + (ix + 0.5) * self.resolution, oy + (iy + 0.5) * self.resolution

    def in_bounds(self, x: float, y: float) -> bool:
        iy, ix = self.world_to_cell(x, y)
        return 0 <= iy < self.height and 0 <= ix < self.width

    def is_free(self, x: float, y: float) -> bool:
        """True when the point is on the map and its cell is free."""
        iy, ix = self.world_to_cell(x, y)
        if not (0 <= iy < self.height and 0 <= ix < self.width):
            return False
        return not bool(self.occupied[iy, ix])

    def clearance(self, x: float, y: float) -> float:
        """Distance (m) from the point's cell to the nearest occupied cell (0 if occupied
        or off the map)."""
        iy, ix = self.world_to_cell(x, y)
        if not (0 <= iy < self.height and 0 <= ix < self.width):
            return 0.0
        return float(self.distance_field()[iy, ix])

    def distance_field(self) -> NDArray[np.float64]:
        """Euclidean distance (m) of every cell to the nearest occupied cell; cached."""
        if self._free_distance is None:
            dist = ndimage.distance_transform_edt(~self.occupied) * self.resolution
            object.__setattr__(self, "_free_distance", np.asarray(dist, dtype=np.float64))
        assert self._free_distance is not None
        return self._free_distance

    def inflated(self, radius: float) -> OccupancyGrid:
        """A grid where every cell within ``radius`` metres of an obstacle is occupied
        (the configuration space of a round robot of that radius)."""
        blocked = self.distance_field() <= radius
        return OccupancyGrid(blocked | self.occupied, self.resolution, self.origin)

    def line_of_sight(self, x0: float, y0: float, x1: float, y1: float) -> bool:
        """True when the straight segment between two points crosses no occupied cell.

        Exact grid traversal (Amanatides & Woo): every cell the segment passes through
        is visited, in order, stopping at the first occupied one, so no wall however
        thin is stepped over. Points off the map or on its outermost cells count as
        obstructed. Pure Python on purpose: for the short segments robots ask about it
        is several times faster than a vectorised sampler, whose cost is mostly
        per-call overhead.
        """
        return self._traverse(x0, y0, x1, y1, False) >= 0.0

    def ray_clearance(self, x0: float, y0: float, x1: float, y1: float) -> float:
        """-1 when the segment is obstructed; otherwise a lower bound (m, may be 0) on
        the distance from any point of the segment to any occupied cell. A segment
        whose ends each move less than this stays unobstructed (every point of the
        moved segment is within that displacement of the old one)."""
        return self._traverse(x0, y0, x1, y1, True)

    def _ray(self, x0: float, y0: float, x1: float, y1: float) -> traversal.Ray | None:
        """Set-up of the exact grid traversal of the segment (see
        :func:`~mrcomm.world.traversal.ray_setup`); None when an end is off the map or on
        its outermost cells."""
        height, width = self.occupied.shape
        ox, oy = self.origin
        ray = traversal.setup(self.resolution, ox, oy, width, height, x0, y0, x1, y1)
        return None if ray[1] < 0 else ray

    def walls_between(
        self, x0: float, y0: float, x1: float, y1: float, min_gap: float = 0.3
    ) -> int:
        """How many walls the straight segment crosses: the runs of occupied cells it
        passes through, by the same exact traversal as :meth:`line_of_sight`. A wall
        several cells thick is one wall, and so are occupied runs separated by less than
        ``min_gap`` metres of free cells (a ray grazing along a wall steps in and out of
        its cells: that is one wall, not dozens). Ends off the map or on its outermost
        cells count as one wall (the map says nothing about what lies there)."""
        ray = self._ray(x0, y0, x1, y1)
        if ray is None:
            return 1
        # Cells visited, not metres: a diagonal step covers up to √2 cells' width; count
        # the gap in cells of the shorter kind (conservative: gaps merge sooner).
        gap_cells = max(1, math.ceil(min_gap / self.resolution))
        return traversal.walls(self._occupied_cells(), *ray, gap_cells)

    def cast_many(
        self, segments: NDArray[np.float64], count_walls: bool, min_gap: float = 0.3
    ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """For each segment (rows x0, y0, x1, y1) the walls it crosses (0 in line of
        sight; an obstructed one counts 1 unless ``count_walls``, then as
        :meth:`walls_between`) and its clearance (as :meth:`ray_clearance`): the casts
        of one step of the radio's links, in one call."""
        segments = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
        n = len(segments)
        walls = np.zeros(n, dtype=np.int64)
        clearance = np.zeros(n)
        height, width = self.occupied.shape
        ox, oy = self.origin
        gap_cells = max(1, math.ceil(min_gap / self.resolution))
        traversal.cast(
            self._clearances(), self._occupied_cells(), self.resolution, float(ox), float(oy),
            width, height, segments, count_walls, gap_cells, walls, clearance,
        )  # fmt: skip
        return walls, clearance

    def _traverse(self, x0: float, y0: float, x1: float, y1: float, clearances: bool) -> float:
        ray = self._ray(x0, y0, x1, y1)
        if ray is None:
            return -1.0  # ends on the map's outermost cells or beyond: obstructed
        res = self.resolution
        # One array holds both answers: an occupied cell is at distance 0 from the
        # nearest occupied cell, a free one at least a cell's width away.
        nearest = traversal.nearest(self._clearances(), *ray)
        if nearest < 0.0:
            return -1.0
        if not clearances:
            return 0.0
        # Cell-centre distances; a point in a cell is up to half a diagonal from its
        # centre, and so is the nearest point of the occupied cell: subtract both.
        return max(0.0, nearest - math.sqrt(2.0) * res)

    def line_of_sight_many(
        self, starts: NDArray[np.float64], ends: NDArray[np.float64]
    ) -> NDArray[np.bool_]:
        """Line of sight for N segments (``starts``, ``ends``: shape (N, 2)); the same
        exact traversal as :meth:`line_of_sight`, segment by segment."""
        starts = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
        ends = np.asarray(ends, dtype=np.float64).reshape(-1, 2)
        return np.array(
            [
                self.line_of_sight(a[0], a[1], b[0], b[1])
                for a, b in zip(starts.tolist(), ends.tolist(), strict=True)
            ],
            dtype=np.bool_,
        )

    def prepare_ray_casts(self) -> None:
        """Build the lookup ray casts use (once per grid, ~0.1 s for an office map), so
        that the first cast inside a timed loop does not pay for it."""
        self._clearances()
        self._occupied_cells()

    def _clearances(self) -> Any:
        """The distance field, flat, as the ray-cast loops read it fastest: a float
        array for the compiled loops, a list for the plain ones (fast scalar indexing);
        cached."""
        if self._clearance_list is None:
            field = self.distance_field().ravel()
            if traversal.KERNEL == "numba":
                values: Any = np.ascontiguousarray(field, dtype=np.float64)
            else:
                # The field holds few distinct values (cell distances): share one float
                # object per value, so the list's targets stay few and cache-resident.
                shared: dict[float, float] = {}
                values = [shared.setdefault(v, v) for v in field.tolist()]
            object.__setattr__(self, "_clearance_list", values)
        return self._clearance_list

    def _occupied_cells(self) -> Any:
        """The occupied cells, flat, as the wall-counting loops read them: one byte a cell
        for the compiled loops (a long ray's reads stay in the caches), a list for the
        plain ones; cached."""
        if self._occupied_list is None:
            flat = self.occupied.ravel()
            compiled = traversal.KERNEL == "numba"
            cells: Any = np.ascontiguousarray(flat) if compiled else flat.tolist()
            object.__setattr__(self, "_occupied_list", cells)
        return self._occupied_list


class LineOfSightCache:
    """Memoised line of sight for one run: segments whose end points fall in the same
    ``quantum``-sized buckets share one answer (ray cast for the first of them).

    Robots that stand still (waiting, holding) ask the same question over and over, so
    most queries are answered without a ray cast. Each run owns its cache, so results
    stay a pure function of the run's history (deterministic).
    """

    def __init__(self, grid: OccupancyGrid, quantum: float = 0.02, max_entries: int = 200_000):
        self.grid = grid
        self._inverse = 1.0 / quantum
        self._max = max_entries
        self._cache: dict[tuple[int, int, int, int], bool] = {}
        self.hits = 0
        self.misses = 0

    def _key(self, x0: float, y0: float, x1: float, y1: float) -> tuple[int, int, int, int]:
        q = self._inverse
        a = (round(x0 * q), round(y0 * q))
        b = (round(x1 * q), round(y1 * q))
        return (*a, *b) if a <= b else (*b, *a)  # symmetric: A sees B iff B sees A

    def line_of_sight(self, x0: float, y0: float, x1: float, y1: float) -> bool:
        key = self._key(x0, y0, x1, y1)
        found = self._cache.get(key)
        if found is not None:
            self.hits += 1
            return found
        self.misses += 1
        if len(self._cache) >= self._max:
            self._cache.clear()
        value = self._cache[key] = self.grid.line_of_sight(x0, y0, x1, y1)
        return value

    def line_of_sight_many(
        self, starts: NDArray[np.float64], ends: NDArray[np.float64]
    ) -> NDArray[np.bool_]:
        """Vectorised form: only the segments not in the cache are ray cast (batched)."""
        out = np.empty(len(starts), dtype=np.bool_)
        keys = [
            self._key(a[0], a[1], b[0], b[1])
            for a, b in zip(starts.tolist(), ends.tolist(), strict=True)
        ]
        missing = []
        for k, key in enumerate(keys):
            found = self._cache.get(key)
            if found is None:
                missing.append(k)
            else:
                out[k] = found
        self.hits += len(keys) - len(missing)
        if missing:
            self.misses += len(missing)
            if len(self._cache) + len(missing) > self._max:
                self._cache.clear()
            idx = np.array(missing)
            visible = self.grid.line_of_sight_many(starts[idx], ends[idx])
            out[idx] = visible
            for k, v in zip(missing, visible.tolist(), strict=True):
                self._cache[keys[k]] = v
        return out
