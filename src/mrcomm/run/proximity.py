"""Near collisions against ground truth: how close the robots really came, recorded by
the simulation and the live world alike, and each robot's judged near collisions
checked against it.

A robot judges a near collision from what it knows — its own localisation and its
mates' last received poses — so with lost or late poses it may react to a mate that is
no longer there, and miss one that is. The recorder keeps, per robot pair, the
intervals in which the two were within the danger radius of each other (true
centre-to-centre distance) and their closest approach in each. A judged near collision
is then:

* **confirmed** when its two robots were within the danger radius within
  :data:`TOLERANCE` of the moment it was judged (the pose it was judged on is up to a
  pose period old, plus its time in transit);
* a **false alarm** otherwise.

A **missed** near collision is an encounter in which two robots came within the event
horizon (the zone where any mate counts, whatever its heading) while a robot recorded no
near collision with that mate from :data:`TOLERANCE` before the encounter to its end;
it counts once for each robot that missed it (team totals sum robots, as the judged
counts do). A robot does not judge while it stands still, stepping aside or in the
grace after resuming, so a close pass then counts as missed: it is a true near collision
the robot's own record does not hold.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from mrcomm.metrics import labels as L
from mrcomm.metrics.compute import TRUTH_COUNTS
from mrcomm.metrics.timeline import Timeline
from mrcomm.net.pair_extent import row_blocks
from mrcomm.run.config import RunConfig

#: How far apart in time a judgement and the truth may be and still match (s).
TOLERANCE = 0.5

#: Rows of the distance matrix searched for near pairs per array operation.
PROXIMITY_ROWS = 256

#: (robot a, robot b, start, end, closest distance) with a before b in team order.
Encounter = tuple[str, str, float, float, float]


def collision_zone(config: RunConfig) -> tuple[float, float] | None:
    """The behaviour's danger radius and event horizon (None for a behaviour without
    near-collision detection: nothing to check)."""
    collision = getattr(config.variant_params("behaviour"), "collision", None)
    if collision is None:
        return None
    return float(collision.danger_radius), float(collision.event_horizon)


def make_proximity(config: RunConfig, robots: Sequence[str]) -> ProximityRecorder | None:
    """The recorder a run's ground truth keeps (None when there is nothing to check)."""
    zone = collision_zone(config)
    return None if zone is None else ProximityRecorder(robots, zone[0])


class ProximityRecorder:
    """Per robot pair, the intervals its robots spent within ``radius`` of each other."""

    def __init__(self, robots: Sequence[str], radius: float) -> None:
        self.robots = tuple(robots)
        self.radius = radius
        # Pair (a, b), a before b in team order -> start of its current interval, and
        # its closest distance in it; in the order the pairs came near, and among pairs
        # that came near at one step row by row (a, then b).
        self._since: dict[tuple[int, int], float] = {}
        self._closest: dict[tuple[int, int], float] = {}
        self._closed: list[Encounter] = []

    def record(self, distance: np.ndarray, now: float) -> None:
        """One step: ``distance`` holds the true distances between nodes (robots first,
        in team order; 0 on the diagonal, as every link state has), from ``now`` on."""
        near = self._near_pairs(distance)
        if not near and not self._since:
            return  # most steps: no pair near, none was
        for pair in [pair for pair in self._since if pair not in near]:
            self._close(pair, now)
        for pair, dk in near.items():
            if pair not in self._since:
                self._since[pair] = now
                self._closest[pair] = dk
            elif dk < self._closest[pair]:
                self._closest[pair] = dk

    def _near_pairs(self, distance: np.ndarray) -> dict[tuple[int, int], float]:
        """The robot pairs (a, b), a before b, within the radius, row by row, with their
        distance. Read from the matrix's upper triangle a block of rows at a time: at
        10,000 robots a step gathering all 50 million pairs into one array took 0.4 GB."""
        n = len(self.robots)
        near: dict[tuple[int, int], float] = {}
        for a, b in row_blocks(n, PROXIMITY_ROWS):
            block = distance[a:b, :n]
            hits = block <= self.radius
            if np.count_nonzero(hits) == b - a:
                continue  # only the diagonal (0): most steps, most blocks
            rows, columns = np.nonzero(hits)
            rows += a
            upper = columns > rows
            rows, columns = rows[upper], columns[upper]
            values = block[rows - a, columns].tolist()
            near.update(zip(zip(rows.tolist(), columns.tolist(), strict=True), values, strict=True))
        return near

    def _close(self, pair: tuple[int, int], end: float) -> None:
        start = self._since.pop(pair)
        closest = self._closest.pop(pair)
        a, b = self.robots[pair[0]], self.robots[pair[1]]
        self._closed.append((a, b, start, end, round(closest, 4)))

    def encounters(self, end: float) -> list[Encounter]:
        """Every interval, those still open closed at ``end``, in order of start."""
        still_open = [
            (self.robots[i], self.robots[j], s, end, round(self._closest[(i, j)], 4))
            for (i, j), s in self._since.items()
        ]
        return sorted(self._closed + still_open, key=lambda e: (e[2], e[0], e[1]))


def judged_against_truth(
    timeline: Timeline, encounters: Iterable[Encounter], event_horizon: float
) -> dict[str, int]:
    """A robot's judged near collisions checked against the encounters: confirmed,
    false alarms, and encounters within the event horizon it missed."""
    robot = timeline.owner
    by_mate: dict[str, list[tuple[float, float, float]]] = {}
    for a, b, start, end, closest in encounters:
        if robot in (a, b):
            by_mate.setdefault(b if a == robot else a, []).append((start, end, closest))
    judged = [
        (e.time, str(e.data.get("mate", "")))
        for e in timeline.events
        if e.label == L.NEAR_COLLISION
    ]
    confirmed = sum(
        1
        for t, mate in judged
        if any(s - TOLERANCE <= t <= e + TOLERANCE for s, e, _ in by_mate.get(mate, ()))
    )
    missed = 0
    for mate, spans in by_mate.items():
        times = [t for t, m in judged if m == mate]
        for start, end, closest in spans:
            if closest > event_horizon:
                continue
            if not any(start - TOLERANCE <= t <= end + TOLERANCE for t in times):
                missed += 1
    counts = (confirmed, len(judged) - confirmed, missed)
    return dict(zip(TRUTH_COUNTS, counts, strict=True))
