"""The console's hand on the operator, the same in simulation and live mode: the
commands the page queues (from the page's thread), applied by the thread that steps the
operator; the lines the operator's own doings add to the events; the replies the page
shows (refused commands)."""

from __future__ import annotations

import queue
from collections.abc import Callable

from mrcomm.agents.operator import Operator

Command = tuple[str, str, str, tuple[float, float] | None]  # kind, robot, task, where


class OperatorDesk:
    def __init__(self, operator: Operator, on_end: Callable[[], None] | None = None) -> None:
        """``on_end``: what the command ``end`` does (None: there is no ending a
        mission from this console)."""
        self.operator = operator
        self.on_end = on_end
        self.notes: list[str] = []
        self.events: list[str] = []
        self._commands: queue.Queue[Command] = queue.Queue()
        self._logged = 0

    def submit(
        self, kind: str, robot: str = "", task: str = "", where: tuple[float, float] | None = None
    ) -> None:
        """Queue an operator command (any thread); it is sent by :meth:`apply`."""
        self._commands.put((kind, robot, task, where))

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
