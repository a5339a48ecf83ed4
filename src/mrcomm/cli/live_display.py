"""What ``mrcomm live`` shows while the mission runs, on stderr (stdout stays for the
result, or its JSON): mission clock, tasks completed and robots present, read from the
journals (:mod:`mrcomm.live.progress`). A bar on a terminal; otherwise one plain line
every ``PLAIN_PERIOD`` s of wall time (batch logs, pipes)."""

from __future__ import annotations

import time
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn

from mrcomm.live.progress import JournalFollower

PLAIN_PERIOD = 10.0


class LiveDisplay:
    def __init__(self, record_dir: Path, max_time: float, n_tasks: int, n_robots: int) -> None:
        self.follower = JournalFollower(record_dir)
        self.max_time = max_time
        self.n_tasks = n_tasks
        self.n_robots = n_robots
        self.console = Console(stderr=True)
        self.live = self.console.is_terminal
        self.progress = Progress(
            TextColumn("[bold]live[/] mission clock"),
            BarColumn(),
            TextColumn("{task.completed:.0f}/{task.total:.0f} s"),
            TextColumn("· tasks {task.fields[tasks]} · robots {task.fields[robots]}"),
            TimeElapsedColumn(),
            console=self.console,
            disable=not self.live,
        )
        self.task: TaskID | None = None
        self.last_line = time.monotonic()

    def __enter__(self) -> LiveDisplay:
        self.progress.start()
        self.task = self.progress.add_task(
            "live", total=self.max_time, tasks=self._tasks(0), robots=self._robots(0)
        )
        return self

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()

    def _tasks(self, done: int) -> str:
        return f"{done}/{self.n_tasks} done"

    def _robots(self, alive: int) -> str:
        return f"{alive}/{self.n_robots} present"

    def update(self) -> None:
        state = self.follower.poll()
        tasks, robots = self._tasks(state.tasks_done), self._robots(state.robots_alive)
        if self.task is not None:
            self.progress.update(
                self.task, completed=min(state.sim_time, self.max_time), tasks=tasks, robots=robots
            )
        now = time.monotonic()
        if not self.live and now - self.last_line >= PLAIN_PERIOD:
            self.last_line = now
            self.console.print(
                f"live: mission clock {state.sim_time:.0f}/{self.max_time:.0f} s, tasks {tasks}, "
                f"robots {robots}",
                markup=False,
                highlight=False,
            )
