"""Link state of every ordered pair of agents, computed once per step for all pairs.

For each pair: distance, line of sight (ray cast on the map, only when the threshold
needs it), RSSI (from the active threshold's signal model, where it has one),
``warning`` (threshold crossed) and ``connected`` (within the network type's limit).
A node without a position (a virtual assigner) is always connected and never warns.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mrcomm.net.network import AH_RANGE_M, NetworkType
from mrcomm.net.thresholds import BoolArray, FloatArray, Threshold
from mrcomm.world.occupancy import LineOfSightCache, OccupancyGrid


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
    ) -> None:
        self.ids = ids
        self.grid = grid
        self.network = network
        self.threshold = threshold
        self.ah_range = ah_range
        n = len(ids)
        iu = np.triu_indices(n, k=1)
        self._pairs_i, self._pairs_j = iu
        self._eye = np.eye(n, dtype=np.bool_)
        self.sight = LineOfSightCache(grid)

    def update(self, positions: NDArray[np.float64], now: float) -> LinkState:
        """``positions``: (n, 2), NaN rows for nodes without a position."""
        diff = positions[:, None, :] - positions[None, :, :]
        distance = np.sqrt((diff**2).sum(axis=2))
        line_of_sight: BoolArray | None = None
        if self.threshold.needs_line_of_sight:
            line_of_sight = self._line_of_sight(positions, distance)
        rssi, warning = self.threshold.evaluate(distance, line_of_sight, now)
        if self.network is NetworkType.AH:
            with np.errstate(invalid="ignore"):
                connected = ~(distance > self.ah_range)  # NaN (virtual) stays connected
        else:
            connected = np.ones(distance.shape, dtype=np.bool_)
        warning = warning & ~self._eye
        return LinkState(self.ids, distance, line_of_sight, rssi, warning, connected)

    def _line_of_sight(self, positions: FloatArray, distance: FloatArray) -> BoolArray:
        # Only pairs within the network's reach matter for signal (beyond the AH limit
        # nothing is delivered anyway), which keeps the ray casts short.
        n = len(self.ids)
        los = np.ones((n, n), dtype=np.bool_)
        i, j = self._pairs_i, self._pairs_j
        d = distance[i, j]
        reach = self.ah_range if self.network is NetworkType.AH else np.inf
        cast = np.isfinite(d) & (d > 0.0) & (d <= reach)
        if cast.any():
            ci, cj = i[cast], j[cast]
            visible = self.sight.line_of_sight_many(positions[ci], positions[cj])
            los[ci, cj] = visible
            los[cj, ci] = visible
        far = np.isfinite(d) & (d > reach)
        los[i[far], j[far]] = False
        los[j[far], i[far]] = False
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
