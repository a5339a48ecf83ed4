"""The task type of a mission (the task file): world data that the task file holds
and that the assigner sends to the robots (so it is also a wire struct)."""

from __future__ import annotations

import msgspec


class TaskSpec(msgspec.Struct, frozen=True):
    """One task of the mission (the task file)."""

    task_id: str
    type: str
    x: float
    y: float
    arrival_time: float = 0.0
    num_robots: int = 1
    duration: float = 0.0
    depends: tuple[str, ...] = ()
