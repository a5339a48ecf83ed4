"""The operator console on a live mission: the page served by the operator's own team
process (``mrcomm live --console``), showing what reaches the operator over Zenoh and
sending its commands. There is no ground truth in that process and the world sets the
pace, so the page has neither.

The operator process steps its agent on the world's clock; at each step
:meth:`LiveConsole.on_step` applies the commands the page queued and, every
:data:`~mrcomm.console.session.VIEW_PERIOD` of wall time, replaces the snapshot the
page reads.
"""

from __future__ import annotations

import queue
import time
from typing import TYPE_CHECKING

from mrcomm.console.session import VIEW_PERIOD, Command
from mrcomm.console.view import ConsoleView, operator_snapshot

if TYPE_CHECKING:
    from mrcomm.agents.operator import Operator
    from mrcomm.world.occupancy import OccupancyGrid


class LiveConsole:
    speed: float | None = None  # the world sets the pace
    waiting = False
    has_truth = False

    def __init__(self, operator: Operator, grid: OccupancyGrid, counts: dict[str, object]) -> None:
        self.operator = operator
        self.grid = grid
        self.robot_ids = operator.robots
        self.notes: list[str] = []
        self.events: list[str] = []
        self._counts = counts  # the operator's endpoint counts, per topic (live)
        self._commands: queue.Queue[Command] = queue.Queue()
        self._logged = 0
        self._heard = 0
        self._next_view = 0.0
        self.view: ConsoleView = operator_snapshot(operator, 0.0, [], {})

    def submit(
        self, kind: str, robot: str = "", task: str = "", where: tuple[float, float] | None = None
    ) -> None:
        self._commands.put((kind, robot, task, where))

    def on_step(self, now: float) -> None:
        """Called by the operator's process at each step, before the operator steps."""
        while True:
            try:
                kind, robot, task, where = self._commands.get_nowait()
            except queue.Empty:
                break
            try:
                self.operator.command(kind, robot, task, where)
            except ValueError as err:
                self.notes.append(f"{now:.1f} s: {kind} refused: {err}")
        for record in self.operator.log[self._logged :]:
            what = " ".join(p for p in (str(record.command), record.robot, record.task_id) if p)
            self.events.append(f"{record.time:7.1f} operator sent {what}")
        self._logged = len(self.operator.log)
        heard = list(self.operator.successes.items())
        for (task_id, robot), when in heard[self._heard :]:
            self.events.append(f"{when:7.1f} operator heard task {task_id} done by {robot}")
        self._heard = len(heard)
        wall = time.monotonic()
        if wall >= self._next_view:
            self._next_view = wall + VIEW_PERIOD
            self.publish(now)

    def publish(self, now: float, *, ended: bool = False) -> None:
        counters = {
            topic: {"sent": c.sent, "received": c.received,  # type: ignore[attr-defined]
                    "dropped": c.dropped_loss + c.dropped_range}  # type: ignore[attr-defined]
            for topic, c in sorted(self._counts.items())
        }  # fmt: skip
        view = operator_snapshot(self.operator, now, self.events, counters)
        if ended:
            from dataclasses import replace

            view = replace(view, ended=True)
        self.view = view
