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
from mrcomm.net.thresholds import upper_pairs
from mrcomm.run.config import RunConfig

#: How far apart in time a judgement and the truth may be and still match (s).
TOLERANCE = 0.5

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
        self._pairs = upper_pairs(len(self.robots))  # (shared with the link recorder)
        self._since: dict[int, float] = {}  # pair index -> start of its current interval
        self._closest: dict[int, float] = {}
        self._closed: list[Encounter] = []

    def record(self, distance: np.ndarray, now: float) -> None:
        """One step: ``distance`` holds the true distances between nodes (robots first,
        in team order), from ``now`` on."""
        i, j = self._pairs
        if len(i) == 0:
            return
        d = distance[i, j]
        near = np.flatnonzero(d <= self.radius)
        if not len(near) and not self._since:
            return  # most steps: no pair near, none was
        near_set = set(near.tolist())
        for k in [k for k in self._since if k not in near_set]:
            self._close(k, now)
        for k, dk in zip(near.tolist(), d[near].tolist(), strict=True):
            if k not in self._since:
                self._since[k] = now
                self._closest[k] = dk
            elif dk < self._closest[k]:
                self._closest[k] = dk

    def _close(self, k: int, end: float) -> None:
        i, j = self._pairs
        start = self._since.pop(k)
        closest = self._closest.pop(k)
        a, b = self.robots[int(i[k])], self.robots[int(j[k])]
        self._closed.append((a, b, start, end, round(closest, 4)))

    def encounters(self, end: float) -> list[Encounter]:
        """Every interval, those still open closed at ``end``, in order of start."""
        i, j = self._pairs
        still_open = [
            (self.robots[int(i[k])], self.robots[int(j[k])], s, end, round(self._closest[k], 4))
            for k, s in self._since.items()
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
