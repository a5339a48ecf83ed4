"""Reporting back (LF's ``reporting`` state): where a robot with nothing left to do
goes when the task assigner missed one of its completions (AON left the assigner out
when its lease ran out, so the status counts as lost until the assigner has it).

It drives to the assigner — its base station, or the last known position of the robot
it runs on — and AON brings the assigner up to date as soon as it is heard. A robot's
last known position may be old: reached (within ``REACH``), unreachable, or stalled
on the way for ``AIM_TIMEOUT``, without the assigner heard, the robot goes on to the last known
positions of its other mates, the most recently heard first (one of them may be near
the assigner, or carry the status there: AON re-sends a status to every member short
of it), and starts the round again once it has been everywhere.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

#: A place counts as visited this close (m), ...
REACH = 2.0
#: ... or once the robot has not moved by ``STALL_DISTANCE`` for this long (s): a robot
#: standing there, or a knot on the way, may block it.
AIM_TIMEOUT = 30.0
STALL_DISTANCE = 1.0  # m

Point = tuple[float, float]
#: The tour's name for where the assigner is.
ASSIGNER = "assigner"


def report_places(
    mates: Mapping[str, Point], heard: Mapping[str, float], assigner: Point | None
) -> tuple[dict[str, Point], list[str]]:
    """The places of a report tour and their order: the assigner (when its position is
    known), then the mates' last known positions, the most recently heard first."""
    places = dict(mates)
    order = sorted(places, key=lambda mate: -heard.get(mate, -math.inf))
    if assigner is not None:
        places[ASSIGNER] = assigner
        order.insert(0, ASSIGNER)
    return places, order


class ReportTour:
    """The places a reporting robot has been to, and where it goes next."""

    def __init__(self) -> None:
        self.visited: set[str] = set()
        self.aim: str | None = None
        self._moved_at = (0.0, (math.inf, math.inf))  # when, and from where, it last moved

    def reset(self) -> None:
        self.visited.clear()
        self.aim = None
        self._moved_at = (0.0, (math.inf, math.inf))

    def target(
        self,
        own: Point,
        places: Mapping[str, Point],
        order: list[str],
        now: float,
        *,
        failed: bool,
    ) -> Point | None:
        """The place to drive to: the first of ``order`` (names of ``places``) not yet
        visited; the current one counts as visited once reached, when the drive there
        ``failed`` or stalled. None when there is nowhere to go."""
        if math.dist(own, self._moved_at[1]) > STALL_DISTANCE:
            self._moved_at = (now, own)
        if self.aim is not None:
            where = places.get(self.aim)
            late = now - self._moved_at[0] > AIM_TIMEOUT
            if where is None or failed or late or math.dist(own, where) <= REACH:
                self.visited.add(self.aim)
                self.aim = None
        if self.aim is None:
            left = [name for name in order if name in places and name not in self.visited]
            if not left and self.visited:
                self.visited.clear()  # been everywhere: start again
                left = [name for name in order if name in places]
            self.aim = left[0] if left else None
            self._moved_at = (now, own)
        return None if self.aim is None else places[self.aim]
