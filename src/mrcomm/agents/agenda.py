"""A robot's agenda rules: which of its tasks are available now (arrived, dependencies
reported done by any robot) and which of them to do next (the closest; ties by task
id). NB picks its next task this way and an LF leader the task it leads to."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from mrcomm.world.geometry import Pose
from mrcomm.world.tasks import TaskSpec


def available(tasks: Iterable[TaskSpec], elapsed: float, done: set[str]) -> list[TaskSpec]:
    """The tasks that have arrived ``elapsed`` s into the mission and whose
    dependencies are all in ``done``."""
    return [
        t for t in tasks if t.arrival_time <= elapsed + 1e-9 and all(d in done for d in t.depends)
    ]


def closest(tasks: Sequence[TaskSpec], pose: Pose) -> TaskSpec:
    """The task closest to ``pose`` (greedy agenda), ties broken by task id."""
    return min(tasks, key=lambda t: (math.hypot(t.x - pose.x, t.y - pose.y), t.task_id))
