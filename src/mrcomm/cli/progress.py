"""The progress line long commands show while they work (``run``, ``check``, ``report``,
``scenario make``, ``radio fit``; ``sweep`` and ``live`` have displays of their own).

One line on stderr, redrawn in place: a bar, what is done, and the command's own status
(a mission's clock, tasks, robots, rate and ETA). Only on a terminal: nothing when stderr
is piped or redirected, nothing with ``--json`` or ``--quiet`` (the caller passes
``enabled=False``), so logs and scripts see exactly what they saw before.
"""

from __future__ import annotations

import time
from types import TracebackType
from typing import TYPE_CHECKING

from rich.console import Console
from rich.progress import BarColumn, Progress, SpinnerColumn, TaskID, TextColumn, TimeElapsedColumn

if TYPE_CHECKING:
    from mrcomm.sim.mission import Mission

#: Fewest seconds between two redraws of a mission's line (its status is computed then).
MISSION_PERIOD_S = 0.25


class ProgressLine:
    """A progress line (see the module docstring); a context manager. ``total`` None:
    a spinner instead of a bar (work of unknown length)."""

    def __init__(
        self, label: str, total: float | None, *, enabled: bool = True, status: str = ""
    ) -> None:
        self.console = Console(stderr=True)
        self.enabled = enabled and self.console.is_terminal
        columns = [SpinnerColumn(), TextColumn(f"[bold]{label}[/]")]
        if total is not None:
            columns.append(BarColumn(bar_width=16))
        # Elapsed before the status: on a narrow terminal the status's end is cut, not it.
        columns += [TimeElapsedColumn(), TextColumn("{task.fields[status]}")]
        self.progress = Progress(*columns, console=self.console, disable=not self.enabled,
                                 transient=True)  # fmt: skip
        self.total = total
        self.status = status
        self.task: TaskID | None = None

    def __enter__(self) -> ProgressLine:
        if self.enabled:
            self.progress.start()
            self.task = self.progress.add_task("", total=self.total, status=self.status)
        return self

    def __exit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.progress.stop()

    def update(self, completed: float | None = None, status: str = "") -> None:
        if self.task is not None:
            self.progress.update(self.task, completed=completed, status=status)


class MissionProgress:
    """A simulated mission's line: simulated clock against the time limit, tasks whose
    status the assigner has heard, robots, speed (× real time) and an ETA — the sooner
    of the tasks' pace (time per task so far, for those left) and the time limit.
    Passed to ``Mission.run``."""

    def __init__(self, line: ProgressLine) -> None:
        self.line = line
        self.next_draw = 0.0
        #: Wall and mission clocks at the first step: the rate leaves out the loading.
        self.first: tuple[float, float] | None = None

    def __call__(self, mission: Mission) -> None:
        wall = time.perf_counter()
        if self.first is None:
            self.first = (wall, mission.now)
        if wall < self.next_draw:
            return
        self.next_draw = wall + MISSION_PERIOD_S
        self.line.update(mission.now, self.status(mission, wall - self.first[0], self.first[1]))

    @staticmethod
    def status(mission: Mission, wall_s: float, since: float = 0.0) -> str:
        """The status text, ``wall_s`` seconds after the mission clock read ``since``."""
        now, limit = mission.now, mission.config.max_time
        total = len(mission.resources.scenario.tasks)
        done = len({task for task, _ in mission.assigner.success_received})
        robots = len(mission.resources.scenario.robots)
        text = f"{now:,.0f}/{limit:,.0f} s · tasks heard {done}/{total} · {robots} robots"
        if wall_s <= 0 or now <= since:
            return text
        rate = (now - since) / wall_s
        end = limit if done == 0 else min(limit, now * total / done)
        eta = max(0.0, end - now) / rate
        return f"{text} · ×{rate:,.0f} real time · ETA {_clock(eta)}"


def _clock(seconds: float) -> str:
    minutes, secs = divmod(round(seconds), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"
