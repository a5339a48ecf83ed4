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

import time
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

from mrcomm.console.desk import OperatorDesk
from mrcomm.console.session import VIEW_PERIOD
from mrcomm.console.view import ConsoleView, counters_of, operator_snapshot
from mrcomm.net.delivery import TopicCounts

if TYPE_CHECKING:
    from mrcomm.agents.operator import Operator
    from mrcomm.world.occupancy import OccupancyGrid


class LiveConsole:
    speed: float | None = None  # the world sets the pace
    waiting = False
    has_truth = False

    def __init__(
        self, operator: Operator, grid: OccupancyGrid, counts: Mapping[str, TopicCounts]
    ) -> None:
        """``counts``: the operator's endpoint counts per topic (updated as it runs)."""
        self.operator = operator
        self.grid = grid
        self.robot_ids = operator.robots
        self.desk = OperatorDesk(operator)
        self.submit = self.desk.submit
        self._counts = counts
        self._heard = 0
        self._next_view = 0.0
        self.view: ConsoleView = operator_snapshot(operator, 0.0, [], {})

    def on_step(self, now: float) -> None:
        """Called by the operator's process at each step, before the operator steps."""
        self.desk.apply(now)
        self.desk.log_commands()
        heard = list(self.operator.successes.items())
        for (task_id, robot), when in heard[self._heard :]:
            self.desk.events.append(f"{when:7.1f} operator heard task {task_id} done by {robot}")
        self._heard = len(heard)
        wall = time.monotonic()
        if wall >= self._next_view:
            self._next_view = wall + VIEW_PERIOD
            counters = counters_of(self._counts.items())
            view = operator_snapshot(self.operator, now, self.desk.events, counters)
            self.view = replace(view, notes=tuple(list(self.desk.notes)[-5:]))
