"""Occupancy grid: the map as a boolean array, world/cell conversion, inflation and
line-of-sight ray casting.

Convention: ``occupied[iy, ix]`` with ``iy = 0`` the row at the map origin (the bottom of
the ROS map image; map IO flips rows). Cell ``(iy, ix)`` covers
``[origin_x + ix*res, origin_x + (ix+1)*res) x [origin_y + iy*res, ...)``.
Unknown cells of a ROS map count as occupied.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A static occupancy grid in the map frame."""

    occupied: NDArray[np.bool_]
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)
    _free_distance: NDArray[np.float64] | None = field(default=None, repr=False, compare=False)

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
        """True when the straight segment between two points crosses no occupied cell."""
        return bool(self.line_of_sight_many(np.array([[x0, y0]]), np.array([[x1, y1]]))[0])

    def line_of_sight_many(
        self, starts: NDArray[np.float64], ends: NDArray[np.float64]
    ) -> NDArray[np.bool_]:
        """Vectorised line of sight for N segments (``starts``, ``ends``: shape (N, 2)).

        Samples every segment at a quarter of a cell, so a wall one cell thick is never
        stepped over. Points off the map count as obstructed. Each segment is sampled by
        its own length, so the answer for a segment never depends on the others in the
        batch (vectorised and scalar calls agree exactly).
        """
        starts = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
        ends = np.asarray(ends, dtype=np.float64).reshape(-1, 2)
        if len(starts) == 0:
            return np.zeros(0, dtype=np.bool_)
        lengths = np.hypot(*(ends - starts).T)
        per_segment = np.ceil(lengths / (self.resolution * 0.25)).astype(np.int64) + 2
        # Shorter segments repeat their end point (t clipped at 1) to fill the batch.
        steps = np.arange(int(per_segment.max()), dtype=np.float64)
        t = np.minimum(steps[None, :] / (per_segment[:, None] - 1), 1.0)
        pts = starts[:, None, :] + (ends - starts)[:, None, :] * t[:, :, None]
        ox, oy = self.origin
        ix = np.floor((pts[..., 0] - ox) / self.resolution).astype(np.int64)
        iy = np.floor((pts[..., 1] - oy) / self.resolution).astype(np.int64)
        inside = (ix >= 0) & (ix < self.width) & (iy >= 0) & (iy < self.height)
        hit = np.ones_like(inside)
        hit[inside] = self.occupied[iy[inside], ix[inside]]
        return ~hit.any(axis=1)
