"""Per-robot timeline: labelled intervals on named tracks, plus point events.

Every time-based metric is computed from these records, and the same records
draw the timeline chart. A *track* holds mutually exclusive states (e.g. the
``activity`` track: init / moving / delay / task / waiting / idle); different tracks may
overlap in time (e.g. the LF ``role`` track). Each robot records its own timeline
(distributed data recording).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

ACTIVITY = "activity"
ROLE = "role"


@dataclass(frozen=True)
class Interval:
    track: str
    label: str
    start: float
    end: float

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass(frozen=True)
class Event:
    time: float
    label: str
    data: dict[str, Any] = field(default_factory=dict)


class Timeline:
    """Labelled intervals and events of one robot, recorded as the run goes."""

    def __init__(self, owner: str) -> None:
        self.owner = owner
        self.intervals: list[Interval] = []
        self.events: list[Event] = []
        self._open: dict[str, tuple[str, float]] = {}

    def state(self, track: str) -> str | None:
        """Label currently open on a track (None when nothing is open)."""
        current = self._open.get(track)
        return current[0] if current else None

    def set_state(self, track: str, label: str | None, now: float) -> None:
        """Close the interval open on ``track`` (if any) and open ``label`` (unless None).

        Setting the label that is already open does nothing, so callers may repeat it.
        """
        current = self._open.get(track)
        if current is not None:
            if current[0] == label:
                return
            self._close(track, current, now)
        if label is not None:
            self._open[track] = (label, now)

    def event(self, label: str, now: float, **data: Any) -> None:
        self.events.append(Event(now, label, data))

    def close_all(self, now: float) -> None:
        """End every open interval (at the end of the run)."""
        for track, current in list(self._open.items()):
            self._close(track, current, now)

    def _close(self, track: str, current: tuple[str, float], now: float) -> None:
        label, start = current
        del self._open[track]
        if now > start:
            self.intervals.append(Interval(track, label, start, now))

    # -- queries -------------------------------------------------------------------
    def total(self, label: str, track: str = ACTIVITY) -> float:
        """Total time spent in ``label`` on ``track`` (closed intervals only)."""
        return sum(i.duration for i in self.intervals if i.track == track and i.label == label)

    def count(self, label: str) -> int:
        return sum(1 for e in self.events if e.label == label)

    def first(self, label: str) -> Event | None:
        return next((e for e in self.events if e.label == label), None)

    def last(self, label: str) -> Event | None:
        return next((e for e in reversed(self.events) if e.label == label), None)

    def to_records(self) -> dict[str, list[dict[str, Any]]]:
        """Plain data for JSON / database rows."""
        return {
            "intervals": [
                {"track": i.track, "label": i.label, "start": i.start, "end": i.end}
                for i in self.intervals
            ],
            "events": [{"time": e.time, "label": e.label, **e.data} for e in self.events],
        }
