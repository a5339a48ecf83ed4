"""Distributed data recording (issue 7 §3): every live process writes its own journal.

A journal is a JSON-lines file ``<process>.<incarnation>.jsonl`` in the record
directory, one object per line with a kind ``k``. Lines are buffered and flushed to
the kernel at every clock tick, so a process killed with SIGKILL loses at most the
current tick. What a robot records about itself:

* its timeline as it grows (``iv`` intervals, ``ev`` events) and the intervals open
  at each flush (``open``), so a killed incarnation's last activity can be closed;
* its message log (``msg``: time, topic, sender, sequence, outcome) and cumulative
  counts (``counts``), AON statistics (``aon``);
* its clock (the shared clock, or its host's: ``live.host_clock``) against its host's
  wall clock (``clock``), from which collection estimates each host's clock offset;
* for the task assigner: every task status it received (``status_rx``).
"""

from __future__ import annotations

import glob
import json
import secrets
import socket
import time
from pathlib import Path
from typing import IO, Any

from mrcomm.metrics.timeline import ACTIVITY, ROLE, Timeline
from mrcomm.net.zenoh_node import Presence

#: Outcome codes of the message log (short: the log has a line per delivery).
OUTCOME_CODE = {
    "received": "r",
    "dropped_loss": "l",
    "dropped_range": "x",
    "dropped_radio": "p",
    "dropped_queue": "q",
}


def journal_path(record_dir: Path, process: str, incarnation: int) -> Path:
    return record_dir / f"{process}.{incarnation}.jsonl"


#: Random low bits of an incarnation (below the start time's milliseconds): kept to 11
#: so that incarnations stay below 2**53 and survive JSON readers that use doubles.
INCARNATION_RANDOM_BITS = 11


def new_incarnation(record_dir: Path | None, process: str) -> int:
    """A number ``process`` never used before: its start time in milliseconds in the
    high bits (so a process's incarnations sort in start order, as collection expects),
    random low bits (two starts in one millisecond differ), and greater than every
    incarnation of it journalled in ``record_dir`` — so a clock that stepped back
    cannot make a restarted process reuse an incarnation, which AON would take for the
    old one (and report finished what it dropped as stale)."""
    bits = INCARNATION_RANDOM_BITS
    value = ((time.time_ns() // 1_000_000) << bits) | secrets.randbits(bits)
    if record_dir is not None and record_dir.is_dir():
        for path in record_dir.glob(f"{glob.escape(process)}.*.jsonl"):
            middle = path.name[len(process) + 1 : -len(".jsonl")]
            if middle.isdigit():
                value = max(value, int(middle) + 1)
    return value


class Journal:
    """Append-only JSON-lines writer of one process incarnation."""

    def __init__(self, path: Path) -> None:
        self.path = path
        # Opened by start(): a process that fails before joining leaves no journal.
        self._file: IO[str] | None = None
        self._dirty = False

    def write(self, kind: str, **data: Any) -> None:
        if self._file is None:
            return
        data["k"] = kind
        self._file.write(json.dumps(data, separators=(",", ":"), default=_jsonable))
        self._file.write("\n")
        self._dirty = True

    def flush(self) -> None:
        if self._file is not None and self._dirty:
            self._file.flush()
            self._dirty = False

    def close(self) -> None:
        if self._file is not None:
            self._file.flush()
            self._file.close()
            self._file = None

    def start(self, **data: Any) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = self.path.open("a", encoding="utf-8")
        self.write("start", host=socket.gethostname(), wall=time.time(), **data)


def _jsonable(value: Any) -> Any:
    if isinstance(value, (set, frozenset, tuple)):
        return list(value)
    return str(value)


class TimelineTail:
    """Writes what a timeline recorded since the last call (timelines only grow)."""

    TRACKS = (ACTIVITY, ROLE)

    def __init__(self, timeline: Timeline, journal: Journal) -> None:
        self.timeline = timeline
        self.journal = journal
        self._intervals = 0
        self._events = 0
        self._open: dict[str, tuple[str, float]] = {}
        self._last_flush = -float("inf")

    def flush(self, now: float) -> None:
        tl = self.timeline
        robot = tl.owner
        for interval in tl.intervals[self._intervals :]:
            self.journal.write(
                "iv",
                robot=robot,
                track=interval.track,
                label=interval.label,
                start=interval.start,
                end=interval.end,
            )
        self._intervals = len(tl.intervals)
        for event in tl.events[self._events :]:
            self.journal.write(
                "ev", robot=robot, time=event.time, label=event.label, data=event.data
            )
        self._events = len(tl.events)
        # Open intervals: the label on each track, and since when it has been seen
        # open (an interval closed since then ends where the new one starts).
        changed = False
        for track in self.TRACKS:
            label = tl.state(track)
            previous = self._open.get(track)
            if label is None:
                if previous is not None:
                    del self._open[track]
                    changed = True
                continue
            if previous is None or previous[0] != label:
                start = self._last_end(track, now)
                self._open[track] = (label, start)
                changed = True
        self._last_flush = now
        if changed:
            self.journal.write(
                "open",
                robot=robot,
                time=now,
                intervals=[[t, lab, s] for t, (lab, s) in sorted(self._open.items())],
            )

    def _last_end(self, track: str, now: float) -> float:
        # An interval that closed on this track since the last flush ended when the
        # new one began; otherwise the new one began within this step.
        for interval in reversed(self.timeline.intervals):
            if interval.track == track:
                if self._last_flush <= interval.end <= now:
                    return interval.end
                break
        return now


def track_presence(
    present: dict[str, set[int]], presence: Presence, journal: Journal, now: float
) -> None:
    """Apply a liveliness change to ``present`` (agent -> live incarnations) and journal it."""
    incarnations = present.setdefault(presence.agent, set())
    if presence.alive:
        incarnations.add(presence.incarnation)
    else:
        incarnations.discard(presence.incarnation)
    journal.write(
        "presence",
        time=now,
        agent=presence.agent,
        incarnation=presence.incarnation,
        alive=presence.alive,
    )
