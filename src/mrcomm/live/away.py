"""Noticing that an agent process was away (stopped with SIGSTOP, frozen, its host
suspended) for longer than the Zenoh link lease, and what it does when it is back.

Two silences, both measured on the host's monotonic clock:

* its own loop stood still (:meth:`AwayWatch.loop`): the process itself did not run.
  Its peers closed their links to it when the lease ran out, and its session's
  transports are stale: it reopens its team session (``ZenohNode.reopen``; a peer
  that re-dialed while it was stopped could otherwise stay cut off from it for good);
* no clock tick reached it (:meth:`AwayWatch.tick`): it was away, or the world was.
  Statuses published around then — its own or its mates' — may never have arrived.
  A second and a sixth second later (reconnecting takes a second or two) it reports
  its completed tasks again and asks the team what it completed meanwhile
  (:meth:`AwayWatch.due`; ``TaskExecutor.rejoined``, ``Resync.catch_up``).
"""

from __future__ import annotations

#: Wall seconds after a silence between ticks at which to report and ask again.
REPORT_AFTER = (2.0, 6.0)


class AwayWatch:
    """The two silences of one process (see the module docstring)."""

    def __init__(self, lease: float) -> None:
        """``lease``: the Zenoh link lease (wall s); a longer silence means away."""
        self.lease = lease
        self._last_loop: float | None = None
        self._last_tick: float | None = None
        self._due: list[float] = []  # monotonic wall times to report and ask again

    def loop(self, wall: float) -> float | None:
        """One pass of the process's loop at monotonic ``wall``: the wall seconds it
        stood still before, when longer than the lease (else None)."""
        last, self._last_loop = self._last_loop, wall
        return wall - last if last is not None and wall - last > self.lease else None

    def tick(self, wall: float) -> float | None:
        """A clock tick taken at ``wall``: the wall seconds without one before, when
        longer than the lease (else None); the re-reports are then scheduled."""
        last, self._last_tick = self._last_tick, wall
        if last is None or wall - last <= self.lease:
            return None
        self._due = [wall + after for after in REPORT_AFTER]
        return wall - last

    def due(self, wall: float) -> bool:
        """Whether a scheduled re-report is due at ``wall`` (each is due once)."""
        if self._due and wall >= self._due[0]:
            self._due.pop(0)
            return True
        return False
