"""The task assigner credits a robot only with what that robot reported: a member's
status naming another robot (sent plainly, or carried by AON) is refused and counted.
With robot_3's certificate, an intruder once had robot_1's and robot_2's tasks credited
while it paused them (the result said successful with 2 of 7 tasks done)."""

from __future__ import annotations

from mrcomm.agents.assigner import TaskAssigner
from mrcomm.messaging.messages import TOPIC_TASK_STATUS, TaskSpec, TaskState, TaskStatus
from tests.agents.fakes import FakeBus

TASKS = [TaskSpec(str(i), "SENSOR_SWEEP", float(i), 0.0) for i in range(1, 4)]


def status(sender: str, robot: str, task: str) -> TaskStatus:
    return TaskStatus(sender=sender, incarnation=1, seq=int(task), stamp=1.0, robot=robot,
                      task_id=task, state=TaskState.SUCCESS)  # fmt: skip


def test_a_status_of_another_robot_is_refused() -> None:
    bus = FakeBus("assigner")
    assigner = TaskAssigner(bus, ("robot_1", "robot_2", "robot_3"), TASKS)
    bus.deliver(TOPIC_TASK_STATUS, status("robot_3", "robot_1", "1"))  # forged
    bus.deliver(TOPIC_TASK_STATUS, status("robot_2", "robot_2", "2"))  # its own
    assert set(assigner.success_received) == {("2", "robot_2")}
    assert assigner.refused == {"status of another robot": 1}
