"""One-lane passages of a map: doors and corridors too narrow for two robots to pass
each other, found on the occupancy grid, with the lookups robots queue by (which
passage a point is in, which passages lie near a point).

A free cell is *narrow* when the free run through it along some direction (the two
axes and the two diagonals) is shorter than ``max_width``: in a door the run along the
wall is the door's width, while a cell in a room or a wide corridor has long runs every
way. A connected group of narrow cells is a passage when it joins at least two separate
wider areas (a door joins two rooms; a nook or a gap behind furniture joins one and is
left out). Its *axis* is the way through it: from the centre of the wider cells on one
side to those on the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrcomm.world.occupancy import OccupancyGrid

#: A side area must have at least this many cells to count (a cell or two in a wall's
#: corner is not a room).
MIN_SIDE_CELLS = 4
_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class Passage:
    """One one-lane passage: its centre, its axis (unit vector, the way through), its
    half length along the axis and half width across it (m), and its width (twice the
    largest clearance inside it: a door's width, a corridor's widest point) (m)."""

    index: int
    cx: float
    cy: float
    ax: float
    ay: float
    half_length: float
    half_width: float
    width: float

    def along(self, x: float, y: float) -> float:
        """Signed distance of a point from the centre along the axis."""
        return (x - self.cx) * self.ax + (y - self.cy) * self.ay

    def across(self, x: float, y: float) -> float:
        """Signed distance of a point from the axis."""
        return (y - self.cy) * self.ax - (x - self.cx) * self.ay


class Passages:
    """The one-lane passages of a map and lookups by position."""

    def __init__(
        self,
        grid: OccupancyGrid,
        passages: tuple[Passage, ...],
        cells: dict[int, int],
    ) -> None:
        self.passages = passages
        self._origin = grid.origin
        self.resolution = grid.resolution
        self._width = grid.width
        self._cells = cells  # flat cell index -> passage index
        #: reach -> the lookup of :meth:`near` (made on first use; the same for all
        #: who share the map, so a race between two makes the same one twice).
        self._lookups: dict[float, dict[tuple[int, int], tuple[int, ...]]] = {}

    def __len__(self) -> int:
        return len(self.passages)

    def at(self, x: float, y: float) -> int | None:
        """The passage the point lies in, or None."""
        ox, oy = self._origin
        ix = math.floor((x - ox) / self.resolution)
        iy = math.floor((y - oy) / self.resolution)
        if ix < 0 or iy < 0 or ix >= self._width:
            return None
        return self._cells.get(iy * self._width + ix)

    def near(self, x: float, y: float, reach: float) -> tuple[int, ...]:
        """The passages the point may lie within ``reach`` of, along their axis and
        across it (every one it does; a few farther ones: the lookup is by cells)."""
        return self.lookup(reach).get((math.floor(x * PER_M), math.floor(y * PER_M)), ())

    def lookup(self, reach: float) -> dict[tuple[int, int], tuple[int, ...]]:
        """:meth:`near` as a table of cells of 1 / :data:`PER_M` m (keyed
        ``(floor(x * PER_M), floor(y * PER_M))``), for a caller asking for every robot at
        every step. A cell lists a passage when some point of it lies within ``reach`` of
        the passage's box along the axis and across it (the box grown by ``reach`` and
        the cell overlap), so a robot beside a door down a corridor is not handed the
        door a few metres on."""
        table = self._lookups.get(reach)
        if table is None:
            table = {}
            for passage in self.passages:
                for cell in _cells_touching(passage, reach + LOOKUP_MARGIN):
                    table[cell] = (*table.get(cell, ()), passage.index)
            self._lookups[reach] = table
        return table


#: Grows a passage's box a little for :meth:`Passages.lookup`: a point on the grown
#: box's edge, tested by the caller in its own floating-point arithmetic, is listed.
LOOKUP_MARGIN = 1e-6
#: Cells of :meth:`Passages.lookup` per metre: half-metre cells hand a robot fewer
#: passages it is not near than metre cells (a door lined corridor has one every few
#: metres), in a table of a few thousand cells. A power of two: a point's cell,
#: ``floor(x * PER_M)``, and a cell's corners, ``i / PER_M``, are then exact.
PER_M = 2


def _cells_touching(passage: Passage, reach: float) -> list[tuple[int, int]]:
    """The cells ``(i, j)`` of :meth:`Passages.lookup` (the square from (i, j) to
    (i + 1, j + 1) / :data:`PER_M`) that overlap the passage's box grown by ``reach``
    along its axis and across it: two convex shapes overlap unless one of their four
    edge directions separates them."""
    half_along = passage.half_length + reach
    half_across = passage.half_width + reach
    ax, ay = passage.ax, passage.ay
    # The grown box's extent along x and y (its own edge directions are tested below).
    ex = abs(ax) * half_along + abs(ay) * half_across
    ey = abs(ay) * half_along + abs(ax) * half_across
    cells = []
    size = 1 / PER_M
    for i in range(
        math.floor((passage.cx - ex) * PER_M), math.floor((passage.cx + ex) * PER_M) + 1
    ):
        for j in range(
            math.floor((passage.cy - ey) * PER_M), math.floor((passage.cy + ey) * PER_M) + 1
        ):
            x0, y0 = i * size, j * size
            corners = ((x0, y0), (x0 + size, y0), (x0, y0 + size), (x0 + size, y0 + size))
            along = [passage.along(x, y) for x, y in corners]
            across = [passage.across(x, y) for x, y in corners]
            if min(along) > half_along or max(along) < -half_along:
                continue
            if min(across) > half_across or max(across) < -half_across:
                continue
            cells.append((i, j))
    return cells


def narrow_cells(grid: OccupancyGrid, max_width: float) -> NDArray[np.bool_]:
    """Free cells between two walls closer together than ``max_width`` metres: the
    nearest wall on one side plus the first wall straight the other way add up to
    less (distances between cell centres: one cell more than the gap between the
    walls' faces). Inside a door or a narrow corridor they do; beside a wall of a room, or in
    its corner, the way back across the room is long. Independent of the walls'
    orientation and thickness."""
    free = ~grid.occupied
    res = grid.resolution
    clearance, (wy, wx) = ndimage.distance_transform_edt(free, return_indices=True)
    clearance = clearance * res
    iy, ix = np.nonzero(free & (clearance < max_width / 2))
    dy = (iy - wy[iy, ix]).astype(np.float64)  # from the nearest wall back to the cell
    dx = (ix - wx[iy, ix]).astype(np.float64)
    norm = np.hypot(dx, dy)
    dy, dx = dy / norm, dx / norm
    first = clearance[iy, ix]
    h, w = free.shape
    open_way = np.ones(iy.size, dtype=bool)  # no wall yet along the way back
    steps = math.ceil(max_width / res)
    for k in range(1, steps + 1):
        ty = np.floor(iy + 0.5 + dy * k).astype(np.int64)
        tx = np.floor(ix + 0.5 + dx * k).astype(np.int64)
        inside = (ty >= 0) & (ty < h) & (tx >= 0) & (tx < w)
        hit = ~inside
        hit[inside] = grid.occupied[ty[inside], tx[inside]]
        open_way &= ~(hit & (first + k * res < max_width))
    narrow = np.zeros_like(free)
    narrow[iy[~open_way], ix[~open_way]] = True
    return narrow


def find_passages(grid: OccupancyGrid, max_width: float, min_width: float = 0.0) -> Passages:
    """The one-lane passages of ``grid``: groups of cells narrower than ``max_width``
    (m) that join two or more wider areas. Gaps narrower than ``min_width`` (m; a
    robot's diameter: no robot passes them, as between the ends of two thin walls)
    are left out."""
    if max_width <= 0:
        return Passages(grid, (), {})
    free = ~grid.occupied
    inner = narrow_cells(grid, max_width)
    # Across a wall at an angle to the grid, the cells of a door's line come in pieces
    # (a ray from a jamb through a cell beside the line misses the other jamb): joined
    # by growing them two cells within free space.
    narrow = ndimage.binary_dilation(inner, iterations=2, mask=free)
    wide = free & ~narrow
    # A side must be part of an area of some size: the back of a nook is wide too.
    areas, _ = ndimage.label(wide)
    area_cells = np.bincount(areas.ravel())
    area_cells[0] = 0
    big_area = area_cells * grid.resolution**2 >= max_width**2
    labels, _ = ndimage.label(narrow, structure=_EIGHT)
    passages: list[Passage] = []
    cells: dict[int, int] = {}
    clearance = grid.distance_field()
    res = grid.resolution
    pad = 3
    h, w = labels.shape
    for label, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is None:
            continue
        ys = slice(max(box[0].start - pad, 0), min(box[0].stop + pad, h))
        xs = slice(max(box[1].start - pad, 0), min(box[1].stop + pad, w))
        group = labels[ys, xs] == label
        # Grown through free space only, edge to edge: not through a thin wall.
        ring = ndimage.binary_dilation(group, iterations=3, mask=free[ys, xs])
        ring &= big_area[areas[ys, xs]]
        sides, _ = ndimage.label(ring)  # 4-connected: no slipping through a thin wall
        sizes = np.bincount(sides.ravel())[1:]
        big = [i + 1 for i in np.argsort(sizes)[::-1] if sizes[i] >= MIN_SIDE_CELLS]
        if len(big) < 2:
            continue  # a nook: it opens on one area only
        width = 2 * float(clearance[ys, xs][group & inner[ys, xs]].max(initial=0.0))
        if width < min_width:
            continue
        iy, ix = np.nonzero(group)
        px = grid.origin[0] + (ix + xs.start + 0.5) * res
        py = grid.origin[1] + (iy + ys.start + 0.5) * res
        (a_y, a_x), (b_y, b_x) = (ndimage.center_of_mass(sides == s) for s in big[:2])
        ax, ay = (b_x - a_x), (b_y - a_y)
        norm = math.hypot(ax, ay)
        if norm == 0:
            continue
        ax, ay = ax / norm, ay / norm
        cx, cy = float(px.mean()), float(py.mean())
        along = (px - cx) * ax + (py - cy) * ay
        across = (py - cy) * ax - (px - cx) * ay
        index = len(passages)
        half_width = float(np.abs(across).max()) + res / 2
        passages.append(
            Passage(
                index=index,
                cx=cx,
                cy=cy,
                ax=ax,
                ay=ay,
                half_length=float(np.abs(along).max()) + res / 2,
                half_width=half_width,
                width=width,
            )
        )
        for flat in ((iy + ys.start) * w + (ix + xs.start)).tolist():
            cells[flat] = index
    return Passages(grid, tuple(passages), cells)
