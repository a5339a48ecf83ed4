"""Agent-side link sensors (the :class:`~mrcomm.ports.LinkSensor` port): what a robot
itself can tell about its link to a team mate, from its own pose and the mate's last
known position (SLT, SSD) or from its pulse process's measurements (ESD)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import LineOfSightCache, OccupancyGrid

if TYPE_CHECKING:
    from mrcomm.net.signal.table import RssiTable


class NoSensor:
    """No threshold: never warns."""

    positional = True

    def warning(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> bool:
        return False

    def rssi(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> float | None:
        return None

    def warning_between(self, ax: float, ay: float, bx: float, by: float) -> bool | None:
        return False


class DistanceSensor:
    """SLT: distance stands in for signal strength."""

    positional = True

    def __init__(self, warning_m: float) -> None:
        self.warning_m = warning_m

    def warning(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> bool:
        return self.warning_between(own.x, own.y, peer_x, peer_y)

    def rssi(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> float | None:
        return None

    def warning_between(self, ax: float, ay: float, bx: float, by: float) -> bool:
        return math.hypot(bx - ax, by - ay) > self.warning_m


class ModelSensor:
    """SSD: RSSI predicted by the signal model for the distance, with the line-of-sight
    or obstructed model chosen by ray casting on the robot's own map."""

    positional = True

    def __init__(self, grid: OccupancyGrid, table: RssiTable, warning_dbm: float) -> None:
        self.grid = grid
        self.sight = LineOfSightCache(grid)
        grid.prepare_ray_casts()
        self.table = table
        self.warning_dbm = warning_dbm

    def _rssi_between(self, ax: float, ay: float, bx: float, by: float) -> float | None:
        visible = self.sight.line_of_sight(ax, ay, bx, by)
        return self.table.rssi_at(math.hypot(bx - ax, by - ay), visible)

    def rssi(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> float | None:
        return self._rssi_between(own.x, own.y, peer_x, peer_y)

    def warning(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> bool:
        return bool(self.warning_between(own.x, own.y, peer_x, peer_y))

    def warning_between(self, ax: float, ay: float, bx: float, by: float) -> bool | None:
        value = self._rssi_between(ax, ay, bx, by)
        return value is not None and value < self.warning_dbm


#: A measured RSSI older than this (s) is stale: the pulse stopped reporting that peer.
STALE_AFTER_S = 5.0


class MeasuredSensor:
    """ESD: the latest RSSI per peer measured by the robot's pulse process (live) or
    replayed from a recorded trace (simulation). Unknown peers and stale readings never
    warn."""

    positional = False

    def __init__(self, warning_dbm: float, stale_after: float = STALE_AFTER_S) -> None:
        self.warning_dbm = warning_dbm
        self.stale_after = stale_after
        self.latest: dict[str, tuple[float, float]] = {}  # peer -> (rssi, time)

    def update(self, peer: str, rssi: float, now: float) -> None:
        self.latest[peer] = (rssi, now)

    def rssi(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> float | None:
        reading = self.latest.get(peer)
        if reading is None or now - reading[1] > self.stale_after:
            return None
        return reading[0]

    def warning(self, peer: str, own: Pose, peer_x: float, peer_y: float, now: float) -> bool:
        value = self.rssi(peer, own, peer_x, peer_y, now)
        return value is not None and value < self.warning_dbm

    def warning_between(self, ax: float, ay: float, bx: float, by: float) -> bool | None:
        return None  # only this robot's own links are measured
