"""Round-robin assignment (SPEC §1)."""

import pytest

from mrcomm.agents.assignment import round_robin
from mrcomm.messaging.messages import TaskSpec


def _tasks(n: int, robots_needed: dict[int, int] | None = None) -> list[TaskSpec]:
    needed = robots_needed or {}
    return [
        TaskSpec(str(i), "SENSOR_SWEEP", float(i), 0.0, num_robots=needed.get(i, 1))
        for i in range(1, n + 1)
    ]


def test_three_robots_seven_tasks_matches_the_spec() -> None:
    agenda = round_robin(_tasks(7), ["robot_1", "robot_2", "robot_3"])
    assert [t.task_id for t in agenda["robot_1"]] == ["1", "4", "7"]
    assert [t.task_id for t in agenda["robot_2"]] == ["2", "5"]
    assert [t.task_id for t in agenda["robot_3"]] == ["3", "6"]


def test_multi_robot_task_takes_the_next_robots_in_the_cycle() -> None:
    agenda = round_robin(_tasks(3, {2: 2}), ["a", "b", "c"])
    assert [t.task_id for t in agenda["a"]] == ["1", "3"]
    assert [t.task_id for t in agenda["b"]] == ["2"]
    assert [t.task_id for t in agenda["c"]] == ["2"]
    # the cycle continues after the two robots of task 2: task 4 goes to b
    assert [t.task_id for t in round_robin(_tasks(4, {2: 2}), ["a", "b", "c"])["b"]] == ["2", "4"]


def test_task_needing_more_robots_than_the_team_is_rejected() -> None:
    with pytest.raises(ValueError, match="needs 4 robots"):
        round_robin(_tasks(1, {1: 4}), ["a", "b", "c"])
