"""Which team mates a live agent treats as gone: a mate whose liveliness token vanished
(its process died, or was stopped past its links' lease) or that has been *silent*
past the lease while its token stays.

A token outlives a process that no longer works when only the process's Python side
is stuck (a hung main thread, a deadlock): Zenoh's own threads keep its session and
token alive while nothing is published any more. A robot publishes a pose at every
step it takes, so a robot mate from which no sample at all reached this process (any
topic, counted at the bus edge before the emulated network drops anything: silence
says the process is gone, not that the radio is out of range) for longer than the
Zenoh link lease is treated as gone exactly like a mate whose token vanished — the
same window after which Zenoh itself drops the links of a process that stopped.

Silence is measured on this process's *active* clock: the wall time between its own
steps, each gap counted up to :data:`STEP_GAP_CAP`. A pause of the whole team (the
world stopped: no ticks, so no one steps or publishes) or of this process itself
(stopped, frozen: it hears nothing meanwhile) therefore makes no mate look silent.
A mate is judged only once it has been heard (a robot publishes nothing before its
assignment) and once its token has been seen (before that, nothing is known of it).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

#: Wall seconds at most that one gap between two steps adds to the active clock.
STEP_GAP_CAP = 1.0


class MateWatch:
    """Token presence and silence of the robot mates of one agent process."""

    def __init__(self, mates: Iterable[str], window: float) -> None:
        """``mates``: the robot ids to watch; ``window``: the silence (active wall s)
        after which a mate counts as gone — the link lease."""
        self.mates = tuple(mates)
        self.window = window
        #: Active wall seconds so far (see the module docstring).
        self.clock = 0.0
        self._last_wall: float | None = None
        self._samples: dict[str, int] = {}  # mate -> samples counted when last looked
        self._heard: dict[str, float] = {}  # mate -> active clock when last heard
        #: Mates silent past the window (their token may still be there).
        self.silent: set[str] = set()
        #: Mates currently treated as gone (token vanished, or silent).
        self.gone: set[str] = set()

    def step(self, wall: float, samples: Mapping[str, int]) -> None:
        """One step of this process at monotonic ``wall``; ``samples``: how many samples
        of each sender the bus edge has let through so far (only ever grows)."""
        if self._last_wall is not None:
            self.clock += min(max(wall - self._last_wall, 0.0), STEP_GAP_CAP)
        self._last_wall = wall
        for mate in self.mates:
            count = samples.get(mate, 0)
            if count != self._samples.get(mate, 0):
                self._samples[mate] = count
                self._heard[mate] = self.clock
                self.silent.discard(mate)
            elif mate in self._heard and self.clock - self._heard[mate] > self.window:
                self.silent.add(mate)

    def changes(self, present: Mapping[str, set[int]]) -> list[tuple[str, bool]]:
        """Mates whose standing changed since the last call, as ``(mate, alive)``: alive
        means its token is present and it is not silent. ``present``: each agent's live
        incarnations (a mate with no entry has never been seen: not judged)."""
        out = []
        for mate in self.mates:
            if mate not in present:
                continue
            alive = bool(present[mate]) and mate not in self.silent
            if alive == (mate in self.gone):
                out.append((mate, alive))
                if alive:
                    self.gone.discard(mate)
                else:
                    self.gone.add(mate)
        return out
