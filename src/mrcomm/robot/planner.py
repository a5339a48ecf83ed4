"""Global planner: A* (pyastar2d, C++) on a coarse, conservatively inflated copy of the
map, with extra cost near walls, temporary circular obstacles (team mates), start/goal
snapping and line-of-sight path simplification.

Built once per map and shared by every robot of a run. The planning grid has cells of
``params.planner_resolution`` (a whole multiple of the map's cell); a planning cell is
free only when every map cell inside it keeps ``params.inflation_radius`` from the
nearest obstacle, so a path through free planning cells is safe on the real map.

Simplification keeps the clearance the A* path had: a shortcut from waypoint ``i`` to
``j`` is taken only if its least clearance is at least the least clearance of the raw
path between them (capped at the comfortable clearance, minus half a cell). Shortcuts
therefore do not hug corners that the wall cost kept the raw path away from, which is
what lets a simple path follower cut corners a little without touching walls.

A search runs on a window of the grid around start and goal, not on the whole map, so
its cost follows the route and not the map's area. The result is the whole-grid
search's, exactly: with weights of at least 1 per move and pyastar2d's Chebyshev
heuristic (consistent), every cell A* expands has ``cheb(start, c) + cheb(c, goal)`` at
most the found path's cost ``C``; when that region (plus a cell) lies inside the window,
no expanded cell touches the window's edge, so every expansion sees the same neighbours
in the same order as on the whole grid, and the search pushes and pops exactly the same
entries. A window too small for its path's cost is searched again as large as that cost
requires (at most twice; the whole grid when no path is found in the window).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pyastar2d.astar
from numpy.typing import NDArray

from mrcomm.robot.params import RobotParams
from mrcomm.world.geometry import polyline_length
from mrcomm.world.occupancy import OccupancyGrid

Point = tuple[float, float]
#: (y0, y1, x0, x1): the rows and columns of the planning grid a search runs on.
Window = tuple[int, int, int, int]

#: Windows are used on grids of at least this many cells: on smaller ones the search's
#: own exploration outweighs what a window saves (allocating and filling per-cell
#: arrays), and a route between rooms often leaves its first window (measured on the
#: 400 x 600 cell office S2: 0.70 s of A* with windows, 0.63 s without).
WINDOW_FROM_CELLS = 2_000_000
#: A window is tried when it is smaller than this fraction of the grid (else the whole
#: grid is searched: the result is the same, and a window would save little).
WINDOW_FRACTION = 0.5
#: The first window is made for a path costing this many times the straight line.
FIRST_STRETCH = 1.5
#: A mate blocks a disc of two footprints plus the block margin plus this much (m) in a
#: re-plan around it: one cell of the default 0.1 m grid, fixed so that a coarser grid
#: does not make mates bigger (with one 0.2 m cell, 10 robots on the generated office
#: S2 found fewer ways round each other and LF knotted at a junction in 3 of 15 runs).
MATE_DISC_SLACK = 0.1


def astar_cells(
    weights: NDArray[np.float32], start: tuple[int, int], goal: tuple[int, int]
) -> NDArray[np.int32] | None:
    """pyastar2d's 8-connected A* from cell ``start`` to cell ``goal`` of ``weights``
    (float32, every cost >= 1): the path's cells, or None. The same C search
    ``pyastar2d.astar_path`` calls, without that wrapper's per-call scan for the least
    weight (ours are >= 1 by construction) and its copy of the grid: the C code reads
    the array's memory directly as float32, so it gets a C-contiguous float32 array
    (copied only when it is not one already: a window's slice; the copy a re-plan
    around mates draws is passed as it is)."""
    h, w = weights.shape
    flat = np.ascontiguousarray(weights, dtype=np.float32).ravel()
    path: NDArray[np.int32] | None = pyastar2d.astar.astar(
        flat, h, w, start[0] * w + start[1], goal[0] * w + goal[1], True, 0
    )
    return path


@dataclass(frozen=True)
class PlannedPath:
    """A collision-free polyline: ``waypoints[0]`` is the start, ``waypoints[-1]`` the
    (possibly snapped) goal."""

    waypoints: tuple[Point, ...]
    length: float

    @property
    def goal(self) -> Point:
        return self.waypoints[-1]


#: One mate's blocked disc on the planning grid: the rows y0:y1 and columns x0:x1 of the
#: whole grid it may touch and which of those cells it blocks.
Disc = tuple[int, int, int, int, NDArray[np.bool_]]


class PlanMemo:
    """One robot's last search without mates and its last search around mates: for
    each, what the search depended on (start and goal cells; the cells the mates
    blocked), the cell costs it ran on and the waypoint cells it found (None: no path).
    A robot that resumes where it paused (a knot of mates stops it again before it has
    left its planning cell) asks for the same search again, and one held by mates that
    do not move asks again every re-plan interval for the same search around them —
    which in a crowded office finds no path nearly every time, after expanding every
    cell it can reach. Each answer depends on nothing else, so it is not searched
    again. Owned by the robot, never by the shared planner."""

    __slots__ = ("around", "plain")

    def __init__(self) -> None:
        self.plain = _Remembered()
        self.around = _Remembered()


class _Remembered:
    __slots__ = ("cells", "key", "weights")

    def __init__(self) -> None:
        self.key: object = None
        self.weights: NDArray[np.float32] | None = None
        self.cells: NDArray[np.int32] | None = None


class GridPlanner:
    """A* planner for one map and one robot size, shared by the robots of a run and by
    the runs a worker executes at once in threads (Dask): it never writes its fields
    after construction (a re-plan around mates draws them into copies)."""

    def __init__(self, grid: OccupancyGrid, params: RobotParams) -> None:
        self.grid = grid
        self.params = params
        k = max(1, round(params.planner_resolution / grid.resolution))
        self.k = k
        self.resolution = k * grid.resolution
        self.origin = grid.origin
        self.inflation = params.inflation_radius
        fine = grid.distance_field()
        hc, wc = -(-grid.height // k), -(-grid.width // k)
        # Off-map cells of the padded border count as obstacles (clearance 0).
        padded = np.zeros((hc * k, wc * k), dtype=np.float64)
        padded[: grid.height, : grid.width] = fine
        clear = padded.reshape(hc, k, wc, k).min(axis=(1, 3)).astype(np.float32)
        self._clear: NDArray[np.float32] = clear
        self._weights: NDArray[np.float32] = self._weights_from(clear)
        self.shape = (hc, wc)
        # Map-resolution clearance as a flat memoryview: the simulator's per-step safety
        # check reads one float from it without a numpy call.
        flat = np.ascontiguousarray(fine, dtype=np.float32).tobytes()
        self._fine_view = memoryview(flat).cast("f")
        self._fine_w = grid.width
        self._fine_h = grid.height
        self._fine_inv = 1.0 / grid.resolution

    # ----------------------------------------------------------------- grids
    def _weights_from(self, clear: NDArray[np.float32]) -> NDArray[np.float32]:
        p = self.params
        excess = np.clip((clear - self.inflation) / max(p.wall_cost_range, 1e-9), 0.0, 1.0)
        weights = (1.0 + p.wall_cost_weight * (1.0 - excess) ** 2).astype(np.float32)
        weights[clear <= self.inflation] = np.inf
        return weights

    def tie_break_weights(self, rng: np.random.Generator, amount: float) -> NDArray[np.float32]:
        """A run's own copy of the cell costs, each multiplied by ``1 + amount * u`` with
        ``u`` uniform in [0, 1) (the ``realistic`` profile's tie-break noise): equally
        long routes then differ in cost, and which one A* takes depends on the run's
        seed. Costs stay >= 1 (A*'s heuristic stays admissible) and blocked cells stay
        blocked. Never written into the planner: it is shared by runs in threads."""
        noise = rng.random(self.shape, dtype=np.float32)
        weights: NDArray[np.float32] = self._weights * (
            np.float32(1.0) + np.float32(amount) * noise
        )
        return weights

    @property
    def blocked(self) -> NDArray[np.bool_]:
        """Planning-grid cells the robot's centre may not occupy (copy)."""
        return ~np.isfinite(self._weights)

    def clearance(self, x: float, y: float) -> float:
        """Distance (m) from the map cell holding (x, y) to the nearest obstacle on the
        real map; 0 off the map. Fast scalar lookup for per-step safety checks."""
        ox, oy = self.origin
        fx = (x - ox) * self._fine_inv
        fy = (y - oy) * self._fine_inv
        if fx < 0.0 or fy < 0.0 or fx >= self._fine_w or fy >= self._fine_h:
            return 0.0
        return self._fine_view[int(fy) * self._fine_w + int(fx)]

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """(iy, ix) of the planning cell holding a point (may be off the grid)."""
        ox, oy = self.origin
        return (
            math.floor((y - oy) / self.resolution),
            math.floor((x - ox) / self.resolution),
        )

    def cell_centre(self, iy: int, ix: int) -> Point:
        ox, oy = self.origin
        return ox + (ix + 0.5) * self.resolution, oy + (iy + 0.5) * self.resolution

    def is_free(self, x: float, y: float) -> bool:
        """True when (x, y) is in a free planning cell (centre keeps the inflation)."""
        iy, ix = self.cell_of(x, y)
        hc, wc = self.shape
        return 0 <= iy < hc and 0 <= ix < wc and bool(self._clear[iy, ix] > self.inflation)

    def snap(self, x: float, y: float) -> tuple[int, int] | None:
        """The free planning cell nearest to (x, y) within ``params.max_snap``, or None."""
        return self._snap(x, y, self._clear)

    def _snap(self, x: float, y: float, clear: NDArray[np.float32]) -> tuple[int, int] | None:
        iy, ix = self.cell_of(x, y)
        hc, wc = self.shape
        if 0 <= iy < hc and 0 <= ix < wc and clear[iy, ix] > self.inflation:
            return iy, ix
        m = math.ceil(self.params.max_snap / self.resolution)
        y0, y1 = max(iy - m, 0), min(iy + m + 1, hc)
        x0, x1 = max(ix - m, 0), min(ix + m + 1, wc)
        if y0 >= y1 or x0 >= x1:
            return None
        window = clear[y0:y1, x0:x1] > self.inflation
        if not window.any():
            return None
        ox, oy = self.origin
        cy = (y - oy) / self.resolution - 0.5
        cx = (x - ox) / self.resolution - 0.5
        yy, xx = np.mgrid[y0:y1, x0:x1]
        d2 = np.where(window, (yy - cy) ** 2 + (xx - cx) ** 2, np.inf)
        best = int(np.argmin(d2))
        if d2.flat[best] * self.resolution**2 > (self.params.max_snap + self.resolution) ** 2:
            return None
        return y0 + best // (x1 - x0), x0 + best % (x1 - x0)

    def _window_for(self, s_cell: tuple[int, int], g_cell: tuple[int, int], cost: float) -> Window:
        """The smallest window holding every cell a search whose path costs ``cost`` can
        expand (see the module docstring), a cell beyond it, and the margin float
        rounding of the costs could need; clipped to the grid."""
        hc, wc = self.shape
        dy, dx = abs(s_cell[0] - g_cell[0]), abs(s_cell[1] - g_cell[1])
        slack = cost * 1.001 + 2.0
        my = max(0, math.ceil((slack - dy) / 2)) + 1
        mx = max(0, math.ceil((slack - dx) / 2)) + 1
        return (
            max(0, min(s_cell[0], g_cell[0]) - my),
            min(hc, max(s_cell[0], g_cell[0]) + my + 1),
            max(0, min(s_cell[1], g_cell[1]) - mx),
            min(wc, max(s_cell[1], g_cell[1]) + mx + 1),
        )

    def _first_window(self, s_cell: tuple[int, int], g_cell: tuple[int, int]) -> Window:
        """A first guess, for a path costing ``FIRST_STRETCH`` times the straight line."""
        chebyshev = max(abs(s_cell[0] - g_cell[0]), abs(s_cell[1] - g_cell[1]))
        return self._window_for(s_cell, g_cell, FIRST_STRETCH * chebyshev + 8)

    def _whole(self) -> Window:
        return (0, self.shape[0], 0, self.shape[1])

    def _worth_it(self, window: Window) -> bool:
        y0, y1, x0, x1 = window
        cells = self.shape[0] * self.shape[1]
        return cells >= WINDOW_FROM_CELLS and (y1 - y0) * (x1 - x0) < WINDOW_FRACTION * cells

    def _discs(
        self, obstacles: Sequence[Point], radius: float, starts: Sequence[Point]
    ) -> list[Disc]:
        """The cells each of ``obstacles`` blocks: a disc of ``radius``, never covering
        the start (``starts``: the robot's position, and the centre of the free cell it
        was snapped to when it stands in the inflated zone), or the robot could not
        leave its own cell."""
        res = self.resolution
        hc, wc = self.shape
        cx, cy = self.cell_centre(0, 0)
        discs: list[Disc] = []
        for ox, oy in obstacles:
            near = min(math.hypot(sx - ox, sy - oy) for sx, sy in starts)
            r = min(radius, near - res)
            if r <= 0:
                continue
            iy, ix = self.cell_of(ox, oy)
            m = math.ceil(r / res) + 1
            y0, y1 = max(iy - m, 0), min(iy + m + 1, hc)
            x0, x1 = max(ix - m, 0), min(ix + m + 1, wc)
            if y0 >= y1 or x0 >= x1:
                continue
            # (np.ogrid's rows and columns, made directly: the same numbers, less work)
            yy = np.arange(y0, y1)[:, None]
            xx = np.arange(x0, x1)[None, :]
            inside = ((cx + xx * res - ox) ** 2 + (cy + yy * res - oy) ** 2) <= r * r
            discs.append((y0, y1, x0, x1, inside))
        return discs

    def _with_discs(
        self, discs: Sequence[Disc], base: NDArray[np.float32], window: Window
    ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """Copies of the ``window`` of (``base`` weights, clearance) with ``discs``
        blocked."""
        wy0, wy1, wx0, wx1 = window
        weights = base[wy0:wy1, wx0:wx1].copy()
        clear = self._clear[wy0:wy1, wx0:wx1].copy()
        for y0, y1, x0, x1, inside in discs:
            cy0, cy1, cx0, cx1 = max(y0, wy0), min(y1, wy1), max(x0, wx0), min(x1, wx1)
            if cy0 >= cy1 or cx0 >= cx1:
                continue
            part = inside[cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0]
            weights[cy0 - wy0 : cy1 - wy0, cx0 - wx0 : cx1 - wx0][part] = np.inf
            clear[cy0 - wy0 : cy1 - wy0, cx0 - wx0 : cx1 - wx0][part] = -1.0
        return weights, clear

    def _search(
        self,
        s_cell: tuple[int, int],
        g_cell: tuple[int, int],
        weights: NDArray[np.float32],
        discs: Sequence[Disc],
        local: bool = False,
    ) -> tuple[NDArray[np.int32], NDArray[np.float32], Window] | None:
        """A* from ``s_cell`` to ``g_cell`` with ``discs`` blocked (the whole grid's
        result, searched on a window): the path's cells (whole-grid indices), the
        clearance it was planned on (of the window) and the window; None when there is
        no path. ``local``: search the first window only, whatever the grid's size, and
        return its path (None when it holds none), not necessarily the whole grid's."""
        window = self._first_window(s_cell, g_cell)
        if not local and not self._worth_it(window):
            window = self._whole()
        while True:
            y0, y1, x0, x1 = window
            if discs:
                grid, clear = self._with_discs(discs, weights, window)
                if not (
                    grid[g_cell[0] - y0, g_cell[1] - x0] < np.inf
                    and grid[s_cell[0] - y0, s_cell[1] - x0] < np.inf
                ):
                    return None
            else:
                grid, clear = weights[y0:y1, x0:x1], self._clear[y0:y1, x0:x1]
            raw = astar_cells(
                grid, (s_cell[0] - y0, s_cell[1] - x0), (g_cell[0] - y0, g_cell[1] - x0)
            )
            # The answer stands as it is for a local search or one on the whole grid;
            # otherwise it must be shown to be the whole grid's.
            final = local or window == self._whole()
            if raw is None:
                if final:
                    return None
                window = self._whole()
                continue
            if not final:
                cost = float(grid[raw[1:, 0], raw[1:, 1]].astype(np.float64).sum())
                need = self._window_for(s_cell, g_cell, cost)
                if not (need[0] >= y0 and need[1] <= y1 and need[2] >= x0 and need[3] <= x1):
                    window = need if self._worth_it(need) else self._whole()
                    continue
            raw[:, 0] += y0
            raw[:, 1] += x0
            return raw, clear, window

    # ------------------------------------------------------------- planning
    def plan(
        self,
        start: Point,
        goal: Point,
        obstacles: Sequence[Point] = (),
        obstacle_radius: float | None = None,
        weights: NDArray[np.float32] | None = None,
        memo: PlanMemo | None = None,
        local: bool = False,
    ) -> PlannedPath | None:
        """Shortest safe path from ``start`` to ``goal``, or None when there is none.

        ``obstacles`` are centres of temporary round obstacles (team mates); each blocks
        a disc of ``obstacle_radius`` (default: two footprints plus the block margin and
        :data:`MATE_DISC_SLACK`). Start and goal inside the inflated zone are snapped to the
        nearest free cell first (on the static map: a mate on the goal means no path).
        ``weights``: the run's own cell costs (:meth:`tie_break_weights`) instead of the
        planner's; passed in, never stored, because the planner is shared. ``memo``: the
        robot's :class:`PlanMemo` (a search asked again, without mates or around the
        same blocked cells, is answered from it). ``local``: a short way to a point
        near by (a route's repair, see :class:`~mrcomm.robot.base.SimBase`), searched
        on the small window around start and goal only; None when that window holds
        none (the way round may lie farther out: the caller plans the whole route).
        """
        s_cell = self._snap(*start, self._clear)
        g_cell = self._snap(*goal, self._clear)
        if s_cell is None or g_cell is None:
            return None
        if weights is None:
            weights = self._weights
        if obstacle_radius is None:
            p = self.params
            obstacle_radius = 2 * p.radius + p.block_margin + MATE_DISC_SLACK
        discs: list[Disc] = []
        if obstacles:
            # A start in the inflated zone searches from the free cell it was snapped
            # to: a mate's disc must leave that cell open too (in a dead end, say).
            starts = [start]
            if self.cell_of(*start) != s_cell:
                starts.append(self.cell_centre(*s_cell))
            discs = self._discs(obstacles, obstacle_radius, starts)
        # The search depends on the start and goal cells, the costs and the cells the
        # mates block, nothing else: a memo answers a search asked again.
        slot = None if memo is None else (memo.around if obstacles else memo.plain)
        key = (
            None
            if slot is None
            else (s_cell, g_cell, local, tuple((*d[:4], d[4].tobytes()) for d in discs))
        )
        if slot is not None and slot.key == key and slot.weights is weights:
            cells = slot.cells
        else:
            found = self._search(s_cell, g_cell, weights, discs, local)
            cells = None
            if found is not None:
                raw, clear, window = found
                cells = raw[self._simplify(raw, clear, (window[0], window[2]))]
            if slot is not None:
                slot.key, slot.weights, slot.cells = key, weights, cells
        if cells is None:
            return None
        pts: list[Point] = [self.cell_centre(int(iy), int(ix)) for iy, ix in cells.tolist()]
        # The robot starts where it is, not at a cell centre; same for an exact goal.
        s_exact = self.cell_of(*start) == s_cell
        g_exact = self.cell_of(*goal) == g_cell
        first = (float(start[0]), float(start[1]))
        pts = [first, *pts[1:]] if s_exact else [first, *pts]
        if len(pts) == 1:
            pts.append(pts[0])
        if g_exact:
            pts[-1] = (float(goal[0]), float(goal[1]))
        waypoints = tuple((float(px), float(py)) for px, py in pts)
        return PlannedPath(waypoints, polyline_length(waypoints))

    def _simplify(
        self, raw: NDArray[np.int32], clear: NDArray[np.float32], corner: tuple[int, int]
    ) -> list[int]:
        """Indices of the raw A* cells kept as waypoints (``raw`` in whole-grid cells,
        ``clear`` a window of the clearance whose first cell is ``corner``; the geometry
        is computed in whole-grid cells, so the window changes no rounding).

        Douglas-Peucker on the validity test: a span is kept as one segment when the
        shortcut is valid, else split at the raw cell farthest from the chord. All spans
        of one level are tested in a single vectorised call, so a path costs a handful
        of numpy calls (one per level), not one per candidate shortcut.
        """
        n = len(raw)
        if n <= 2:
            return list(range(n))
        comfort = self.inflation + self.params.wall_cost_range
        tol = 0.5 * self.resolution
        # The raw cells' clearance, and one cell more for the span minima (see below).
        c = np.append(clear[raw[:, 0] - corner[0], raw[:, 1] - corner[1]], np.inf).astype(
            np.float64
        )
        centres = raw.astype(np.float64) + 0.5
        # Whether the shortcut over each span tested so far is valid (a function of the
        # span alone): the passes after Douglas-Peucker often ask about a span it asked.
        tested: dict[tuple[int, int], bool] = {}

        def test(spans: list[tuple[int, int]]) -> list[bool]:
            new = [span for span in spans if span not in tested]
            if new:
                starts = np.array([i for i, _ in new])
                ends = np.array([j for _, j in new])
                need = self._needs(c, starts, ends, comfort, tol)
                ok = self._segments_ok(centres, clear, corner, starts, ends, need)
                tested.update(zip(new, ok.tolist(), strict=True))
            return [tested[span] for span in spans]

        keep = {0, n - 1}
        spans = [(0, n - 1)]
        while spans:
            nxt: list[tuple[int, int]] = []
            for (i, j), valid in zip(spans, test(spans), strict=True):
                if valid or j - i <= 1:
                    continue
                m = self._farthest(centres, i, j)
                keep.add(m)
                nxt.append((i, m))
                nxt.append((m, j))
            spans = nxt
        kept = sorted(keep)
        # Douglas-Peucker splits where a shortcut first fails, which can leave a
        # waypoint that a longer shortcut would skip: try dropping each one (every
        # other waypoint per pass, so the tests of one pass are independent).
        for parity in (1, 2, 1, 2):
            if len(kept) <= 2:
                break
            mids = list(range(parity, len(kept) - 1, 2))
            if not mids:
                continue
            spans = [(kept[k - 1], kept[k + 1]) for k in mids]
            drop = {kept[k] for k, valid in zip(mids, test(spans), strict=True) if valid}
            kept = [k for k in kept if k not in drop]
        return kept

    @staticmethod
    def _needs(
        c: NDArray[np.float64],
        starts: NDArray[np.int64],
        ends: NDArray[np.int64],
        comfort: float,
        tol: float,
    ) -> NDArray[np.float64]:
        """The clearance each shortcut from cell ``starts[k]`` to ``ends[k]`` must keep:
        the least clearance of the raw cells from start to end inclusive (``c``: theirs,
        and one more cell after the last), capped at ``comfort``, less ``tol``."""
        # reduceat over [start, end + 1) for each span: the even entries of an
        # interleaved index list (the odd ones, from one span's end to the next span's
        # start, are discarded; spans may share an end, which reduceat allows).
        bounds = np.empty(2 * len(starts), dtype=np.int64)
        bounds[0::2] = starts
        bounds[1::2] = ends + 1
        least = np.minimum.reduceat(c, bounds)[0::2]
        return np.minimum(least, comfort) - tol

    @staticmethod
    def _farthest(centres: NDArray[np.float64], i: int, j: int) -> int:
        """Index strictly between i and j of the cell farthest from the chord i-j."""
        a = centres[i]
        d = centres[j] - a
        rel = centres[i + 1 : j] - a
        dist = np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0])
        return i + 1 + int(np.argmax(dist))

    def _segments_ok(
        self,
        centres: NDArray[np.float64],
        clear: NDArray[np.float32],
        corner: tuple[int, int],
        starts: NDArray[np.int64],
        ends: NDArray[np.int64],
        need: NDArray[np.float64],
    ) -> NDArray[np.bool_]:
        """For each span k: does the straight segment from cell ``starts[k]`` to cell
        ``ends[k]`` stay in free cells with at least ``need[k]`` clearance? Sampled every
        half cell along the longer axis (the clearance field changes by at most one cell
        size per cell, which the tolerance in ``need`` absorbs)."""
        a = centres[starts]
        b = centres[ends]
        counts = (np.ceil(np.abs(b - a).max(axis=1) * 2.0) + 2).astype(np.int64)
        offsets = np.zeros(len(counts), dtype=np.int64)
        np.cumsum(counts[:-1], out=offsets[1:])
        seg = np.repeat(np.arange(len(counts)), counts)
        t = (np.arange(int(counts.sum())) - offsets[seg]) / (counts[seg] - 1)
        pts = a[seg] + (b - a)[seg] * t[:, None]
        rows = pts[:, 0].astype(np.int64) - corner[0]
        cols = pts[:, 1].astype(np.int64) - corner[1]
        vals = clear[rows, cols]
        least = np.minimum.reduceat(vals, offsets)
        return (least > self.inflation) & (least >= need)
