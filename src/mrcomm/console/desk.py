"""The console's hand on the operator, the same in simulation and live mode: the
commands the page queues (from the page's thread), applied by the thread that steps the
operator; the lines the operator's own doings add to the events; the replies the page
shows (refused commands).

What a page can make it hold is bounded: commands are accepted at :data:`RATE` a second
(bursts of :data:`BURST`, wall time: a person clicks), at most :data:`QUEUE_BOUND` wait
to be sent, at most :data:`MAX_COMMANDS` in a mission, and the replies shown are the
last :data:`MAX_NOTES`; what is refused is counted by cause (``refused``) and said.
"""

from __future__ import annotations

import queue
import threading
import time
from collections import Counter, deque
from collections.abc import Callable

from mrcomm.agents.operator import Operator

Command = tuple[str, str, str, tuple[float, float] | None]  # kind, robot, task, where

RATE = 5.0  # commands a second, sustained
BURST = 10  # commands at once
QUEUE_BOUND = 32  # commands waiting for the stepping thread
MAX_COMMANDS = 1000  # commands of one mission
MAX_NOTES = 100  # replies kept for the page


class OperatorDesk:
    def __init__(
        self,
        operator: Operator,
        on_end: Callable[[], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        """``on_end``: what the command ``end`` does (None: there is no ending a
        mission from this console); ``clock``: wall seconds, for the rate."""
        self.operator = operator
        self.on_end = on_end
        self.notes: deque[str] = deque(maxlen=MAX_NOTES)
        self.events: list[str] = []
        #: Commands refused before they were sent, by cause.
        self.refused: Counter[str] = Counter()
        self._commands: queue.Queue[Command] = queue.Queue(QUEUE_BOUND)
        self._logged = 0
        self._clock = clock
        self._tokens = float(BURST)
        self._refilled = clock()
        self._accepted = 0
        self._lock = threading.Lock()

    def submit(
        self, kind: str, robot: str = "", task: str = "", where: tuple[float, float] | None = None
    ) -> bool:
        """Queue an operator command (any thread); it is sent by :meth:`apply`. False
        (and a note) when it is refused: too fast, too many waiting, or too many."""
        with self._lock:
            now = self._clock()
            self._tokens = min(float(BURST), self._tokens + (now - self._refilled) * RATE)
            self._refilled = now
            cause = ""
            if self._accepted >= MAX_COMMANDS:
                cause = f"more than {MAX_COMMANDS} commands in a mission"
            elif self._tokens < 1.0:
                cause = f"more than {RATE:g} commands a second"
            else:
                try:
                    self._commands.put_nowait((kind, robot, task, where))
                except queue.Full:
                    cause = f"{QUEUE_BOUND} commands already waiting"
            if cause:
                self.refused[cause] += 1
                self.notes.append(f"{kind} refused: {cause}")
                return False
            self._tokens -= 1.0
            self._accepted += 1
            return True

    def apply(self, now: float) -> None:
        """Send the queued commands at ``now`` (the stepping thread)."""
        self.operator.set_time(now)
        while True:
            try:
                kind, robot, task, where = self._commands.get_nowait()
            except queue.Empty:
                return
            if kind == "end" and self.on_end is not None:
                self.on_end()
                continue
            try:
                self.operator.command(kind, robot, task, where)
            except ValueError as err:
                self.notes.append(f"{now:.1f} s: {kind} refused: {err}")

    def log_commands(self) -> None:
        """Add the commands sent since the last call to the events."""
        for record in self.operator.log[self._logged :]:
            what = " ".join(p for p in (str(record.command), record.robot, record.task_id) if p)
            self.events.append(f"{record.time:7.1f} operator sent {what}")
        self._logged = len(self.operator.log)
