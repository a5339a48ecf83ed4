"""Link state of every ordered pair of agents, computed once per step for all pairs.

For each pair: distance, line of sight (ray cast on the map, only when the threshold
needs it), RSSI (from the active threshold's signal model, where it has one),
``warning`` (threshold crossed) and ``connected`` (within the network type's limit).
A node without a position (a virtual assigner) is always connected and never warns.

Distance, RSSI, warning and connection are evaluated for every pair at every step.
Line of sight — which of the two signal models applies — only changes when a robot
passes the edge of a wall, so a pair's ray is cast again only when it may have changed:
an unobstructed ray whose clearance to the nearest wall is c stays unobstructed while
each end moves less than c (exact); an obstructed ray is cast again once an end has
moved ``los_refresh`` (0.25 m), so a pair coming into sight through a door switches
model within that distance. Nothing is cast while both ends stand still.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrcomm.net.network import AH_RANGE_M, NetworkType
from mrcomm.net.thresholds import BoolArray, FloatArray, PairGeometry, Threshold
from mrcomm.world.occupancy import OccupancyGrid


@dataclass(frozen=True)
class LinkState:
    ids: tuple[str, ...]
    distance: FloatArray
    line_of_sight: BoolArray | None
    rssi: FloatArray | None
    warning: BoolArray
    connected: BoolArray

    def index(self, agent_id: str) -> int:
        return self.ids.index(agent_id)


class LinkModel:
    """Evaluates every link of the team at each step."""

    def __init__(
        self,
        ids: tuple[str, ...],
        grid: OccupancyGrid,
        network: NetworkType,
        threshold: Threshold,
        *,
        ah_range: float = AH_RANGE_M,
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
        self.ah_range = ah_range
        aliases = dict(aliases or {})
        self.evaluated_ids = tuple(node for node in ids if node not in aliases)
        self._evaluated = np.array([ids.index(node) for node in self.evaluated_ids])
        expand = [self.evaluated_ids.index(aliases.get(node, node)) for node in ids]
        self._expand = np.ix_(expand, expand) if aliases else None
        n = len(self.evaluated_ids)
        iu = np.triu_indices(n, k=1)
        self._pairs_i, self._pairs_j = iu
        self._eye = np.eye(n, dtype=np.bool_)
        self._pairs = list(zip(self._pairs_i.tolist(), self._pairs_j.tolist(), strict=True))
        # Per pair: its ends at the last ray cast, what that cast found, and how far an
        # end may move before the answer may change.
        self._cast_from: list[tuple[float, float, float, float] | None] = [None] * len(self._pairs)
        self._cast_value = [True] * len(self._pairs)
        self._cast_slack = [0.0] * len(self._pairs)
        self.casts = 0

    def update(self, positions: NDArray[np.float64], now: float) -> LinkState:
        """``positions``: (n, 2), NaN rows for nodes without a position."""
        if self._expand is not None:
            positions = positions[self._evaluated]
        diff = positions[:, None, :] - positions[None, :, :]
        distance = np.sqrt((diff**2).sum(axis=2))
        line_of_sight: BoolArray | None = None
        if self.threshold.needs_line_of_sight:
            rows = distance.tolist()
            sight = self._line_of_sight(positions.tolist(), rows)
            pairs = PairGeometry(distance, rows, sight)
            line_of_sight = np.array(sight, dtype=np.bool_)
        else:
            pairs = PairGeometry(distance)
        rssi, warning = self.threshold.evaluate(pairs, now)
        if self.network is NetworkType.AH:
            connected = ~(distance > self.ah_range)  # NaN (virtual) stays connected
        else:
            connected = np.ones(distance.shape, dtype=np.bool_)
        warning = warning & ~self._eye
        if self._expand is not None:
            e = self._expand
            distance, warning, connected = distance[e], warning[e], connected[e]
            line_of_sight = None if line_of_sight is None else line_of_sight[e]
            rssi = None if rssi is None else rssi[e]
        return LinkState(self.ids, distance, line_of_sight, rssi, warning, connected)

    def _line_of_sight(self, xy: list[list[float]], d: list[list[float]]) -> list[list[bool]]:
        # Only pairs within the network's reach matter for signal (beyond the AH limit
        # nothing is delivered anyway). Plain Python: a team has a handful of pairs, and
        # for those it is cheaper than a chain of small numpy operations.
        n = len(xy)
        los = [[True] * n for _ in range(n)]
        reach = self.ah_range if self.network is NetworkType.AH else math.inf
        refresh = self.los_refresh
        done: dict[tuple[float, float, float, float], float] = {}
        for k, (a, b) in enumerate(self._pairs):
            dist = d[a][b]
            if not (0.0 < dist <= reach):  # also False for NaN (virtual node)
                if dist > reach:
                    los[a][b] = los[b][a] = False
                continue
            ends = (xy[a][0], xy[a][1], xy[b][0], xy[b][1])
            last = self._cast_from[k]
            slack = self._cast_slack[k]
            if (
                last is None
                or math.hypot(ends[0] - last[0], ends[1] - last[1]) >= slack
                or math.hypot(ends[2] - last[2], ends[3] - last[3]) >= slack
            ):
                if ends not in done:
                    done[ends] = self.grid.ray_clearance(*ends)
                    self.casts += 1
                clearance = done[ends]
                self._cast_value[k] = clearance >= 0.0
                self._cast_slack[k] = clearance if clearance >= 0.0 else refresh
                self._cast_from[k] = ends
            los[a][b] = los[b][a] = self._cast_value[k]
        return los


class LinkRecorder:
    """Per ordered pair summaries over a run: minimum RSSI, time in warning, time
    disconnected, minimum and maximum distance."""

    def __init__(self, ids: tuple[str, ...], skip: set[tuple[str, str]] | None = None) -> None:
        self.ids = ids
        n = len(ids)
        self._skip = skip or set()
        self.time_warning = np.zeros((n, n))
        self.time_disconnected = np.zeros((n, n))
        self.min_rssi = np.full((n, n), np.inf)
        self.min_distance = np.full((n, n), np.inf)
        self.max_distance = np.zeros((n, n))
        self.warning_onsets = np.zeros((n, n), dtype=np.int64)
        self._prev_warning = np.zeros((n, n), dtype=np.bool_)

    def record(self, state: LinkState, dt: float) -> None:
        self.time_warning += dt * state.warning
        self.time_disconnected += dt * ~state.connected
        self.warning_onsets += state.warning & ~self._prev_warning
        self._prev_warning = state.warning
        if state.rssi is not None:
            np.fmin(self.min_rssi, state.rssi, out=self.min_rssi)
        np.fmin(self.min_distance, state.distance, out=self.min_distance)
        np.fmax(self.max_distance, state.distance, out=self.max_distance)

    def summaries(self) -> dict[str, dict[str, Any]]:
        out: dict[str, dict[str, Any]] = {}
        for i, a in enumerate(self.ids):
            for j, b in enumerate(self.ids):
                if i == j or (a, b) in self._skip:
                    continue
                out[f"{a}->{b}"] = {
                    "min_distance": _finite(self.min_distance[i, j]),
                    "max_distance": _finite(self.max_distance[i, j]),
                    "min_rssi": _finite(self.min_rssi[i, j]),
                    "time_in_warning": round(float(self.time_warning[i, j]), 6),
                    "warnings": int(self.warning_onsets[i, j]),
                    "time_disconnected": round(float(self.time_disconnected[i, j]), 6),
                }
        return out


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None
