"""Where generated robots start and tasks lie: only in the largest region of the map a
robot can drive through (4-connected free cells of the grid inflated by the robot's
radius — the region ``load_scenario`` checks reachability in), with a clearance margin
so the check passes by construction, and spaced apart.

* ``scattered`` — starts drawn uniformly over that region;
* ``clustered`` — all starts packed around one point (like S1's start room);
* ``depots`` — a few depots far apart (farthest-point sampling), robots split among
  them round robin, packed around each.

Spacing is checked with a hash grid of cells one spacing wide, so placing 1000 robots
costs milliseconds. When the region cannot hold what was asked, the error says how many
fit. A caller that knows more (the robots' planning grid) passes which cells are
``usable``: the others are passed over in the same order of draws, so a scenario whose
points were all usable comes out the same.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from mrcomm.errors import InputError
from mrcomm.world.occupancy import OccupancyGrid

Point = tuple[float, float]
#: Clearance beyond the robot's radius of every start and task (m).
MARGIN = 0.15
#: Centre-to-centre distance between starts (m): 0.36 m robots, 0.54 m between them.
START_SPACING = 0.9
#: Between tasks (m).
TASK_SPACING = 1.0
START_MODES = ("clustered", "scattered", "depots")
_CHUNK = 4096  # cells converted to Python floats at a time


def drivable(grid: OccupancyGrid, radius: float) -> NDArray[np.float64]:
    """Cell centres (x, y) of the largest drivable region with clearance > radius +
    MARGIN, as an (n, 2) array in row-major cell order."""
    labels, count = ndimage.label(~grid.inflated(radius).occupied)
    labels = np.asarray(labels)
    if count == 0:
        return np.empty((0, 2))
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    main = labels == int(np.argmax(sizes))
    roomy = main & (grid.distance_field() > radius + MARGIN)
    iy, ix = np.nonzero(roomy)
    res = grid.resolution
    ox, oy = grid.origin
    return np.column_stack([ox + (ix + 0.5) * res, oy + (iy + 0.5) * res])


class Spacer:
    """Accepts points at least ``spacing`` apart (a hash grid of spacing-wide cells)."""

    def __init__(self, spacing: float) -> None:
        self.spacing = spacing
        self.limit = spacing * spacing
        self.cells: dict[tuple[int, int], list[Point]] = {}
        self.points: list[Point] = []

    def _cell(self, p: Point) -> tuple[int, int]:
        return math.floor(p[0] / self.spacing), math.floor(p[1] / self.spacing)

    def take(self, p: Point) -> bool:
        cx, cy = self._cell(p)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for q in self.cells.get((cx + dx, cy + dy), ()):
                    ex, ey = p[0] - q[0], p[1] - q[1]
                    if ex * ex + ey * ey < self.limit:  # exact on every machine (squared_distance)
                        return False
        self.cells.setdefault((cx, cy), []).append(p)
        self.points.append(p)
        return True


def _greedy(candidates: Iterable[Point], count: int, spacer: Spacer) -> int:
    taken = 0
    for p in candidates:
        if taken == count:
            break
        if spacer.take(p):
            taken += 1
    return taken


def squared_distance(cells: NDArray[np.float64], p: Point) -> NDArray[np.float64]:
    """Squared distances from ``p`` to each cell. Not np.hypot: that calls the C
    library, whose last bit may differ between machines and reorder near ties; products
    and sums are exact IEEE operations everywhere, so the same seed draws the same files."""
    dx = cells[:, 0] - p[0]
    dy = cells[:, 1] - p[1]
    return dx * dx + dy * dy


Usable = NDArray[np.bool_] | None


def _in_order(
    cells: NDArray[np.float64], order: NDArray[np.intp], usable: Usable = None
) -> Iterator[Point]:
    """The cells in ``order`` (the ``usable`` ones), lazily: a list of every cell as
    Python tuples would take ~100 bytes a cell (close to 1 GB on a 300 m campus) while
    placement usually stops after a small fraction of them."""
    if usable is not None:
        order = order[usable[order]]
    for k in range(0, len(order), _CHUNK):
        yield from ((x, y) for x, y in cells[order[k : k + _CHUNK]].tolist())


def _nearest_first(
    cells: NDArray[np.float64], centre: Point, usable: Usable = None
) -> Iterator[Point]:
    order = np.argsort(squared_distance(cells, centre), kind="stable")
    return _in_order(cells, order, usable)


def _shuffled(
    cells: NDArray[np.float64], rng: np.random.Generator, usable: Usable = None
) -> Iterator[Point]:
    return _in_order(cells, rng.permutation(len(cells)), usable)


def depot_centres(cells: NDArray[np.float64], count: int, rng: np.random.Generator) -> list[Point]:
    """``count`` points of the region far apart (farthest-point sampling)."""
    first = cells[int(rng.integers(len(cells)))]
    centres = [(float(first[0]), float(first[1]))]
    nearest = squared_distance(cells, centres[0])
    for _ in range(count - 1):
        far = cells[int(np.argmax(nearest))]
        centres.append((float(far[0]), float(far[1])))
        nearest = np.minimum(nearest, squared_distance(cells, centres[-1]))
    return centres


def place_starts(
    cells: NDArray[np.float64],
    count: int,
    mode: str,
    rng: np.random.Generator,
    where: str = "on this map",
    usable: Usable = None,
) -> list[Point]:
    """``count`` start points by ``mode`` (see the module doc) among the ``usable``
    cells; ``where`` names the map in the error message (e.g. "on a 40x30 m
    warehouse")."""
    if len(cells) == 0:
        raise InputError(f"there is no region a robot can drive in {where}", field="--map")
    spacer = Spacer(START_SPACING)
    if mode == "scattered":
        taken = _greedy(_shuffled(cells, rng, usable), count, spacer)
    elif mode == "clustered":
        centre = cells[int(rng.integers(len(cells)))]
        point = (float(centre[0]), float(centre[1]))
        taken = _greedy(_nearest_first(cells, point, usable), count, spacer)
    elif mode == "depots":
        depots = depot_centres(cells, max(2, min(8, count // 25 + 2)), rng)
        queues = [_nearest_first(cells, c, usable) for c in depots]
        taken = 0
        stalled = 0
        while taken < count and stalled < len(queues):
            stalled = 0
            for queue in queues:
                if taken == count:
                    break
                if _greedy(queue, 1, spacer):
                    taken += 1
                else:
                    stalled += 1  # this depot's surroundings are full
    else:
        raise InputError(f"unknown start mode {mode!r}; choose {', '.join(START_MODES)}",
                         field="--start")  # fmt: skip
    if taken < count:
        raise InputError(
            f"{count} robots do not fit {where} (at most ~{taken} starts {START_SPACING:g} m "
            "apart): give a larger --size or fewer --robots",
            field="--robots",
        )
    return spacer.points


def place_tasks(
    cells: NDArray[np.float64],
    count: int,
    rng: np.random.Generator,
    where: str = "on this map",
    usable: Usable = None,
) -> list[Point]:
    """``count`` task locations drawn uniformly over the region (its ``usable`` cells),
    spaced apart."""
    spacer = Spacer(TASK_SPACING)
    taken = _greedy(_shuffled(cells, rng, usable), count, spacer)
    if taken < count:
        raise InputError(
            f"{count} tasks do not fit {where} (at most ~{taken} tasks {TASK_SPACING:g} m "
            "apart): give a larger --size or fewer --tasks",
            field="--tasks",
        )
    return spacer.points
