"""Static round-robin task assignment.

Tasks in file order, robots in a fixed order; each task goes to the next robot in a
cycle (a task needing k robots goes to the next k robots). With 3 robots and 7 tasks:
robot_1 <- {1, 4, 7}, robot_2 <- {2, 5}, robot_3 <- {3, 6}.
"""

from __future__ import annotations

from collections.abc import Sequence

from mrcomm.messaging.messages import TaskSpec


def round_robin(tasks: Sequence[TaskSpec], robots: Sequence[str]) -> dict[str, list[TaskSpec]]:
    if not robots:
        raise ValueError("round-robin assignment needs at least one robot")
    agenda: dict[str, list[TaskSpec]] = {robot: [] for robot in robots}
    cursor = 0
    for task in tasks:
        if task.num_robots > len(robots):
            raise ValueError(f"task {task.task_id} needs {task.num_robots} robots")
        for _ in range(task.num_robots):
            agenda[robots[cursor % len(robots)]].append(task)
            cursor += 1
    return agenda
