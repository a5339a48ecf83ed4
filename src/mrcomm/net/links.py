"""Link state of every ordered pair of agents, computed once per step for all pairs.

For each pair: distance, line of sight (ray cast on the map, only when the threshold
needs it), RSSI (from the active threshold's signal model, where it has one),
``warning`` (threshold crossed) and ``connected`` (within the network type's limit).
With a network model that decides range from received power (``radio``) also the walls
crossed and the received power of every link (``power``), from which it decides
``connected``.
A node without a position (a virtual assigner) is always connected and never warns.

Distance, RSSI, warning and connection are evaluated for every pair at every step.
Line of sight — which of the two signal models applies — only changes when a robot
passes the edge of a wall, so a pair's ray is cast again only when it may have changed:
an unobstructed ray whose clearance to the nearest wall is c stays unobstructed while
each end moves less than c (exact); an obstructed ray is cast again once an end has
moved ``los_refresh`` (0.25 m), so a pair coming into sight through a door switches
model within that distance. Nothing is cast while both ends stand still. Walls are
counted (a full traversal) only when a cast finds the ray obstructed and the network
model needs the count; then an obstructed ray is cast again as soon as an end moves,
so the count is exact at every step (the same count a live receiver casting the one
link a message came over finds: :mod:`mrcomm.net.radio.links`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrcomm.net import pair_loops
from mrcomm.net.network import NetworkModel
from mrcomm.net.pair_extent import PairExtent, row_blocks
from mrcomm.net.thresholds import (
    BoolArray,
    FloatArray,
    PairGeometry,
    PairLayout,
    Threshold,
    upper_pairs,
)
from mrcomm.world.occupancy import OccupancyGrid

RSSI_PERIOD = 0.5  # s between recorded RSSI samples (the pulse rate, 2 Hz)
#: Teams of more than this many robots get sparse per-pair link summaries: a 1000-robot
#: team has a million ordered pairs, almost all of robots that never met.
SPARSE_FROM = 30
#: In a sparse summary, the robot pairs that came at least this close (m) once, ...
SPARSE_NEAR_M = 10.0
#: From this many pairs on, a model that casts no rays computes its distances as one
#: numpy array (``sqrt(dx² + dy²)``, which can differ from Python's ``math.hypot`` in
#: the last bit: a team this large is never one of the original robots' missions).
ARRAY_PAIRS = 64
_NO_NODES = np.zeros(0, dtype=np.int64)
#: An end that moved at least this far (m) has moved.
_MOVED = 1e-12


#: Rows of the distance matrix computed per array operation (see :func:`distance_matrix`):
#: 32 keeps a block's scratch (two arrays of 32 rows) in cache at 10,000 nodes.
DISTANCE_BLOCK = 32


def distance_matrix(at: FloatArray) -> FloatArray:
    """(n, n) distances between the rows (x, y) of ``at``, 0 on the diagonal (NaN for a
    row without a position).

    Each distance is ``sqrt(dx * dx + dy * dy)``: numpy's SIMD square root, ~4 ns a
    value, where ``hypot`` (the C library's, which guards against overflow that map
    coordinates never come near) took ~20 ns. It is within one unit in the last place
    of ``hypot`` (a sixth of the values differ by that). The matrix is computed a block
    of whole rows at a time. It is symmetric bit for bit: a pair's two differences are
    each other's negation and their squares are equal. Computing only the upper
    triangle and mirroring it does half the arithmetic but writes each block down the
    columns, across every row: at 10,000 nodes that took 1.7 s a step, whole rows take
    0.31 s; at 1,000 nodes both take 3.2-3.3 ms."""
    n = len(at)
    out = np.empty((n, n))
    x, y = at[:, 0], at[:, 1]
    for a, b in row_blocks(n, DISTANCE_BLOCK):
        dx = x[a:b, None] - x[None, :]
        dy = y[a:b, None] - y[None, :]
        dx *= dx
        dy *= dy
        dx += dy
        np.sqrt(dx, out=out[a:b])
    np.fill_diagonal(out, 0.0)
    return out


@dataclass(frozen=True)
class LinkState:
    ids: tuple[str, ...]
    distance: FloatArray
    line_of_sight: BoolArray | None
    rssi: FloatArray | None
    warning: BoolArray
    connected: BoolArray
    #: Received power of each link, dBm (network models with a radio; NaN for a node
    #: without a position), else None.
    power: FloatArray | None = None

    def index(self, agent_id: str) -> int:
        return self.ids.index(agent_id)


class LinkModel:
    """Evaluates every link of the team at each step."""

    def __init__(
        self,
        ids: tuple[str, ...],
        grid: OccupancyGrid,
        network: NetworkModel,
        threshold: Threshold,
        *,
        los_refresh: float = 0.25,
        aliases: Mapping[str, str] | None = None,
    ) -> None:
        """``aliases``: node -> node whose position it always shares (a task assigner
        hosted on a robot). Links are evaluated between distinct positions only and
        the alias copies its host's row and column; the threshold sees
        :attr:`evaluated_ids`."""
        self.ids = ids
        self.los_refresh = los_refresh
        self.grid = grid
        self.network = network
        self.threshold = threshold
        aliases = dict(aliases or {})
        self.evaluated_ids = tuple(node for node in ids if node not in aliases)
        index = {node: k for k, node in enumerate(ids)}
        self._evaluated = [index[node] for node in self.evaluated_ids]
        n = len(self.evaluated_ids)
        self.layout = PairLayout(n)
        self._off_diagonal = ~np.eye(n, dtype=np.bool_)
        # Flat indices that expand an evaluated (n, n) matrix to all ids (aliases copy
        # their host's row and column) in one take.
        evaluated = {node: k for k, node in enumerate(self.evaluated_ids)}
        rows = np.array([evaluated[aliases.get(node, node)] for node in ids], dtype=np.intp)
        self._expand = rows[:, None] * n + rows[None, :] if aliases else None
        self._sight: tuple[tuple[bool, ...], BoolArray] | None = None
        self.casts = 0
        self._count_walls = network.needs_walls
        self._casts_rays = threshold.needs_line_of_sight or network.needs_walls
        # Rays are cast pair by pair; without them a large team takes its distances as
        # one matrix and holds nothing per pair (50 million pairs at 10,000 robots).
        self._per_pair = self._casts_rays or self.layout.count < ARRAY_PAIRS
        pairs = self.layout.count if self._per_pair else 0
        self._first, self._second = self.layout.ends if self._per_pair else (_NO_NODES, _NO_NODES)
        # (A small team's pairs without rays, for the loop in Python: see update.)
        python_pairs = self._per_pair and not self._casts_rays
        self._pair_ends = (
            list(zip(self._first.tolist(), self._second.tolist(), strict=True))
            if python_pairs
            else []
        )
        # Per pair: its ends at the last ray cast, what that cast found, and how far an
        # end may move before the answer may change.
        self._cast_from = np.full((pairs, 4), np.nan)  # NaN: never cast
        self._cast_walls = np.zeros(pairs, dtype=np.int64)
        self._cast_slack = np.zeros(pairs)
        self._recast = np.zeros(pairs, dtype=np.int64)
        self._segments = np.zeros((pairs, 4))
        if self._casts_rays:
            grid.prepare_ray_casts()

    def update(
        self, positions: Sequence[Sequence[float]] | NDArray[np.float64], now: float
    ) -> LinkState:
        """``positions``: one (x, y) per id, NaN for nodes without a position."""
        xy = positions.tolist() if isinstance(positions, np.ndarray) else positions
        if self._expand is not None:
            xy = [xy[i] for i in self._evaluated]
        pair_distance: list[float] | None = None
        if not self._per_pair:
            distance = distance_matrix(np.array(xy, dtype=np.float64))
        elif not self._casts_rays:
            # A few pairs (a team of up to 11 robots) in Python: the compiled loop would
            # cost its first caller ~0.3 s of loading numba's machine code, twice a whole
            # S1 mission, for a loop of a few microseconds. The same doubles either way.
            hypot = math.hypot
            pair_distance = [
                hypot(xy[a][0] - xy[b][0], xy[a][1] - xy[b][1]) for a, b in self._pair_ends
            ]
            distance = self.layout.matrix(pair_distance, 0.0)
        else:  # rays are cast: ``at`` and ``distances`` serve below
            at = np.array(xy, dtype=np.float64).reshape(-1, 2)
            distances = np.empty(len(self._first))
            pair_loops.pair_distances(at, self._first, self._second, distances)
            pair_distance = distances.tolist()
            distance = self.layout.matrix(pair_distance, 0.0)
        line_of_sight: BoolArray | None = None
        sight: list[bool] | None = None
        power: FloatArray | None = None
        if self._casts_rays:
            walls = self._walls(at, distances)
            sight = (walls == 0).tolist()
            line_of_sight = self._sight_matrix(sight)
            if self._count_walls:
                power = self._power(xy, distances, walls)
        pairs = PairGeometry(distance, self.layout, pair_distance, sight, power)
        rssi, warning = self.threshold.evaluate(pairs, now)
        warning = warning & self._off_diagonal
        if self._expand is not None:
            e = self._expand
            distance, warning = distance.take(e), warning.take(e)
            line_of_sight = None if line_of_sight is None else line_of_sight.take(e)
            rssi = None if rssi is None else rssi.take(e)
            power = None if power is None else power.take(e)
        if power is None:
            connected = self.network.connected(distance)
        else:
            connected = self.network.in_range_power(power)
        return LinkState(self.ids, distance, line_of_sight, rssi, warning, connected, power)

    def _power(
        self, xy: Sequence[Sequence[float]], distance: FloatArray, walls: NDArray[np.int64]
    ) -> FloatArray:
        """(n, n) received power of the evaluated nodes: the network model's reciprocal
        power per pair plus its per-direction offsets; NaN on the diagonal."""
        network: Any = self.network
        per_pair = network.pair_power(xy, (self._first, self._second), distance, walls)
        matrix = self.layout.matrix(per_pair, math.nan)
        return np.asarray(matrix + network.offsets(len(self.evaluated_ids)))

    def _sight_matrix(self, sight: list[bool]) -> BoolArray:
        # Line of sight changes rarely: rebuild the matrix only when a pair changed.
        key = tuple(sight)
        if self._sight is None or self._sight[0] != key:
            matrix = self.layout.matrix([float(v) for v in sight], 1.0).astype(np.bool_)
            self._sight = (key, matrix)
        return self._sight[1]

    def _walls(self, xy: FloatArray, distance: FloatArray) -> NDArray[np.int64]:
        """Walls crossed by each pair's ray (0: line of sight). Without a wall-counting
        network model an obstructed ray counts as 1 (its exact count is not needed).
        Only pairs within the network's reach are cast: farther pairs count as
        obstructed (beyond the reach nothing is delivered anyway)."""
        walls = np.zeros(len(distance), dtype=np.int64)
        recast = pair_loops.rays_to_cast(
            xy, self._first, self._second, distance, self.network.reach_m, self._cast_from,
            self._cast_slack, self._cast_walls, walls, self._recast, self._segments,
        )  # fmt: skip
        if recast:
            segments = self._segments[:recast]
            counted, clearances = self.grid.cast_many(segments, self._count_walls)
            # Counted walls change wherever the ray crosses a wall's edge: recast an
            # obstructed ray as soon as an end moves (the count is then exact, as a live
            # receiver's fresh cast); only its line of sight may wait ``los_refresh``.
            obstructed_slack = _MOVED if self._count_walls else self.los_refresh
            pair_loops.record_casts(
                self._recast[:recast], segments, counted, clearances, obstructed_slack,
                self._cast_from, self._cast_slack, self._cast_walls, walls,
            )  # fmt: skip
            self.casts += recast
        return walls


def cast_ray(
    grid: OccupancyGrid, ax: float, ay: float, bx: float, by: float, count_walls: bool
) -> tuple[int, float]:
    """One ray cast between two antennas: the walls it crosses (0: line of sight; an
    obstructed ray counts as 1 unless ``count_walls``) and its clearance (-1 when
    obstructed; see :meth:`~mrcomm.world.occupancy.OccupancyGrid.ray_clearance`)."""
    clearance = grid.ray_clearance(ax, ay, bx, by)
    if clearance >= 0.0:
        return 0, clearance
    return (grid.walls_between(ax, ay, bx, by) if count_walls else 1), -1.0


#: Simulated seconds between samples of the team's largest connected group.
GROUP_PERIOD = 0.5


def largest_group(connected: BoolArray) -> int:
    """The most nodes that can all reach each other, directly or through others, over
    links connected in both directions (the largest connected component)."""
    n = len(connected)
    if n == 0:
        return 0
    mutual = connected & connected.T
    if mutual.all():
        return n  # the common case (WLAN, a team in range): no graph search
    from scipy.sparse import csr_matrix  # here: importing scipy.sparse takes a while
    from scipy.sparse.csgraph import connected_components

    _, labels = connected_components(csr_matrix(mutual), directed=False)
    return int(np.bincount(labels).max())


#: Link states of a robot pair by code (0, connected, is not recorded as an interval).
PAIR_STATES = {1: "warning", 2: "out of range"}


class LinkRecorder:
    """What a run's link states add up to — the ground truth recorded by the simulation
    and by the live world alike:

    * per ordered pair: minimum RSSI, time in warning, warning onsets, time disconnected,
      minimum and maximum distance (:meth:`summaries`);
    * per robot (the first ``robots`` ids): its closest and furthest team mate over the
      run (:attr:`min_separation`, :attr:`max_separation`);
    * the RSSI of every robot pair at the pulse rate (2 Hz), where the threshold has one
      (:attr:`rssi_series`);
    * per unordered robot pair, the intervals its link spent in warning or out of range
      (:meth:`state_intervals`; the worse of the two directions);
    * the team's largest connected group at 2 Hz: the most robots that can all reach each
      other, directly or through other robots, over links connected both ways
      (:meth:`connectivity`)."""

    def __init__(
        self,
        ids: tuple[str, ...],
        robots: int,
        skip: set[tuple[str, str]] | None = None,
        rssi_period: float = RSSI_PERIOD,
    ) -> None:
        self.ids = ids
        n = len(ids)
        self._skip = skip or set()
        self.robots = robots
        self.rssi_period = rssi_period
        self._next_rssi = 0.0
        #: (time, from, to, rssi dBm) of robot pairs, sampled every ``rssi_period``.
        self.rssi_series: list[tuple[float, str, str, float]] = []
        self._n = n
        # Per ordered pair, made when a step first adds to them (a WLAN run never warns,
        # disconnects or measures a signal: 3.2 GB of zeros and infinities for 10,000
        # robots); None until then, read as zeros (infinities for the RSSI).
        self._time_warning: NDArray[np.float64] | None = None
        self._warning_onsets: NDArray[np.int64] | None = None
        self._time_disconnected: NDArray[np.float64] | None = None
        self._min_rssi: NDArray[np.float64] | None = None
        self._extent = PairExtent(n)  # each pair's least and greatest distance
        self._prev_warning: BoolArray | None = None  # None: no warning the last step
        # Link state per unordered robot pair (upper triangle): 0 connected, 1 warning,
        # 2 out of range; with when the current state began. Made when a link first
        # warns or breaks (never in a WLAN: 1.25 GB with its pair index at 10,000 robots).
        self._pair_state = np.zeros(0, dtype=np.int8)
        self._pair_since = np.zeros(0)
        self._open_pairs = False  # any pair in warning or out of range
        self._closed: list[tuple[str, str, str, float, float]] = []
        self._next_group = 0.0
        #: The links of the last group sample and its answer (see _largest_group).
        self._group_key: bytes | None = None
        self._group_size = 0
        #: (time, robots in the largest connected group) at :data:`GROUP_PERIOD`.
        self.largest_group: list[tuple[float, int]] = []

    def record(self, state: LinkState, dt: float, now: float) -> list[tuple[str, str, float]]:
        """Add one step of ``dt`` s; return the RSSI samples taken now (usually none)."""
        # Most steps of most runs have no warning and every link connected (a WLAN, a
        # team in range): then the sums below would add zeros, skipped as they would
        # change nothing (n² cells each, a million in a team of 1000).
        warned = bool(state.warning.any())
        if warned:
            if self._time_warning is None or self._warning_onsets is None:
                self._time_warning = np.zeros((self._n, self._n))
                self._warning_onsets = np.zeros((self._n, self._n), dtype=np.int64)
            self._time_warning += dt * state.warning
            previous = self._prev_warning
            self._warning_onsets += state.warning if previous is None else state.warning & ~previous
        self._prev_warning = state.warning if warned else None
        disconnected = not state.connected.all()
        if disconnected:
            if self._time_disconnected is None:
                self._time_disconnected = np.zeros((self._n, self._n))
            self._time_disconnected += dt * ~state.connected
        self._extent.add(state.distance)
        if warned or disconnected or self._open_pairs:
            self._track_pair_states(state, now)
        n = self.robots
        if now >= self._next_group:
            self._next_group += GROUP_PERIOD
            self.largest_group.append((now, self._largest_group(state.connected[:n, :n])))
        if state.rssi is None:
            return []
        if self._min_rssi is None:
            self._min_rssi = np.full((self._n, self._n), np.inf)
        np.fmin(self._min_rssi, state.rssi, out=self._min_rssi)
        if now < self._next_rssi:
            return []
        self._next_rssi += self.rssi_period
        rows = state.rssi[:n, :n].tolist()
        ids = self.ids
        samples = [
            (ids[i], ids[j], rows[i][j])
            for i in range(n)
            for j in range(n)
            if i != j and rows[i][j] == rows[i][j]  # NaN: no RSSI for this pair
        ]
        self.rssi_series.extend((now, a, b, v) for a, b, v in samples)
        return samples

    def _track_pair_states(self, state: LinkState, start: float) -> None:
        """Close the intervals of pairs whose state changed with the step that began at
        ``start`` (the step's states hold from its start)."""
        i, j = upper_pairs(self.robots)
        if len(i) == 0:
            return
        if len(self._pair_state) != len(i):
            self._pair_state = np.zeros(len(i), dtype=np.int8)
            self._pair_since = np.zeros(len(i))
        out = ~state.connected[i, j] | ~state.connected[j, i]
        warn = state.warning[i, j] | state.warning[j, i]
        codes = np.where(out, 2, np.where(warn, 1, 0)).astype(np.int8)
        for k in np.flatnonzero(codes != self._pair_state).tolist():
            self._close(k, start)
            self._pair_state[k] = codes[k]
            self._pair_since[k] = start
        self._open_pairs = bool(self._pair_state.any())

    def _close(self, k: int, end: float) -> None:
        code = int(self._pair_state[k])
        if code and end > self._pair_since[k]:
            first, second = upper_pairs(self.robots)
            a, b = self.ids[first[k]], self.ids[second[k]]
            since = round(float(self._pair_since[k]), 6)
            self._closed.append((a, b, PAIR_STATES[code], since, round(end, 6)))

    def state_intervals(self, end: float) -> list[tuple[str, str, str, float, float]]:
        """(robot a, robot b, "warning" | "out of range", start s, end s) of every robot
        pair's link, in time order, the open ones closed at ``end``."""
        closed = list(self._closed)
        still_open = np.flatnonzero(self._pair_state).tolist()
        if still_open:
            first, second = upper_pairs(self.robots)
            for k in still_open:
                a, b = self.ids[first[k]], self.ids[second[k]]
                since = round(float(self._pair_since[k]), 6)
                if end > since:
                    state = PAIR_STATES[int(self._pair_state[k])]
                    closed.append((a, b, state, since, round(end, 6)))
        return sorted(closed, key=lambda row: (row[3], row[0], row[1]))

    def _largest_group(self, connected: BoolArray) -> int:
        """:func:`largest_group`, searched again only when the links changed since the
        last sample (they rarely do between two; the graph search of scipy cost an
        ad-hoc S1 run about 30 % of its time)."""
        key = connected.tobytes()
        if key != self._group_key:
            self._group_key, self._group_size = key, largest_group(connected)
        return self._group_size

    def connectivity(self) -> dict[str, float | None]:
        """The largest connected group as a fraction of the team: its mean over the
        samples (the run's time) and its minimum; None without a sample."""
        sizes = [size for _, size in self.largest_group]
        if not sizes or self.robots == 0:
            return {"largest_group_mean": None, "largest_group_min": None}
        return {
            "largest_group_mean": round(sum(sizes) / len(sizes) / self.robots, 6),
            "largest_group_min": round(min(sizes) / self.robots, 6),
        }

    @property
    def min_separation(self) -> NDArray[np.float64]:
        """Each robot's closest team mate over the run, m (inf without one): the least
        of its pairs' minimum distances, which is the least over the steps of its
        closest mate in each, exactly (a minimum of minima), kept for free."""
        n = self.robots
        least = [
            self._extent.least_rows(a, b, n).min(axis=1, initial=np.inf) for a, b in row_blocks(n)
        ]
        return np.concatenate([np.zeros(0), *least])

    @property
    def max_separation(self) -> NDArray[np.float64]:
        """Each robot's furthest team mate over the run, m (0 without one)."""
        n = self.robots
        greatest = [
            self._extent.greatest_rows(a, b, n).max(axis=1, initial=0.0) for a, b in row_blocks(n)
        ]
        return np.concatenate([np.zeros(0), *greatest])

    def separations(self) -> list[tuple[float | None, float | None]]:
        """Each robot's closest and furthest team mate over the run, m (6 decimals; None
        without a team mate)."""
        closest, furthest = self.min_separation.tolist(), self.max_separation.tolist()
        return [(_rounded(a), _rounded(b)) for a, b in zip(closest, furthest, strict=True)]

    def summaries(self) -> dict[str, dict[str, Any]]:
        """Per ordered pair ``"a->b"``: distances, lowest RSSI, time in warning, warnings,
        time disconnected. In a team of more than :data:`SPARSE_FROM` robots only the
        pairs that matter: every link to or from a node that is not a robot (the task
        assigner, an operator), and robot pairs that came within
        :data:`SPARSE_NEAR_M` of each other or whose link ever warned; the rest of a
        robot's links are summed up by its closest and furthest mate."""
        kept = ~np.eye(len(self.ids), dtype=np.bool_)
        onsets = self._warning_onsets
        if self.robots > SPARSE_FROM:
            n = self.robots
            for first, end in row_blocks(n):
                kept[first:end, :n] &= self._extent.least_rows(first, end, n) <= SPARSE_NEAR_M
            if onsets is not None:
                kept[:n, :n] |= (onsets[:n, :n] > 0) & ~np.eye(n, dtype=np.bool_)
        time_warning, time_disconnected = self._time_warning, self._time_disconnected
        min_rssi = self._min_rssi
        out: dict[str, dict[str, Any]] = {}
        ids = self.ids
        for i, j in np.argwhere(kept).tolist():  # row by row, as nested loops would
            a, b = ids[i], ids[j]
            if (a, b) not in self._skip:
                out[f"{a}->{b}"] = {
                    "min_distance": _finite(self._extent.least(i, j)),
                    "max_distance": _finite(self._extent.greatest(i, j)),
                    "min_rssi": None if min_rssi is None else _finite(min_rssi[i, j]),
                    "time_in_warning": _sum(time_warning, i, j),
                    "warnings": 0 if onsets is None else int(onsets[i, j]),
                    "time_disconnected": _sum(time_disconnected, i, j),
                }
        return out


def _sum(sums: NDArray[np.float64] | None, i: int, j: int) -> float:
    """A pair's time summed over the steps, s (6 decimals; 0 when nothing was added)."""
    return 0.0 if sums is None else round(float(sums[i, j]), 6)


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def _rounded(value: float) -> float | None:
    return round(float(value), 6) if math.isfinite(value) else None
