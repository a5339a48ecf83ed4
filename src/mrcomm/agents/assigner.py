"""Task assigner agent.

Loads the mission, identifies the team, assigns tasks round-robin at mission start
(the assignment topic is not perturbed), then records, without interfering, every
message it receives. At the end it decides which tasks failed to be communicated: those
whose SUCCESS status from the robot they were assigned to never reached it.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from mrcomm.agents.assignment import round_robin
from mrcomm.agents.commands import CommandInbox, command_team
from mrcomm.messaging.aon import AonEndpoint
from mrcomm.messaging.messages import (
    TOPIC_ASSIGNMENT,
    TOPIC_HEARTBEAT,
    TOPIC_POSE,
    TOPIC_TASK_STATUS,
    Assignment,
    CommandKind,
    Heartbeat,
    Message,
    OperatorCommand,
    TaskSpec,
    TaskState,
    TaskStatus,
)
from mrcomm.ports import BatchHandler, Bus

ASSIGNER_ID = "assigner"
HEARTBEAT_PERIOD = 1.0  # s


class TaskAssigner:
    """Assigns the mission once and records what the team reports."""

    def __init__(
        self,
        bus: Bus,
        team: Sequence[str],
        tasks: Sequence[TaskSpec],
        *,
        incarnation: int = 1,
        use_aon: bool = False,
        aon_lease: float | None = 60.0,
    ) -> None:
        self.bus = bus
        self.team = tuple(team)
        self.tasks = tuple(tasks)
        self.incarnation = incarnation
        self.agenda = round_robin(self.tasks, self.team)
        self.assigned = False
        self.received: Counter[str] = Counter()  # topic -> messages received
        # (task_id, robot) -> time the SUCCESS status first arrived
        self.success_received: dict[tuple[str, str], float] = {}
        self.status_log: list[tuple[float, TaskStatus]] = []
        #: Statuses refused, by cause.
        self.refused: Counter[str] = Counter()
        #: (task_id, robot) -> when an operator's confirmation arrived.
        self.confirmed: dict[tuple[str, str], float] = {}
        self._seq = 0
        self._now = 0.0
        self._next_heartbeat = 0.0
        self.aon: AonEndpoint | None = None
        if use_aon:
            self.aon = AonEndpoint(
                bus,
                bus.owner,
                incarnation,
                (*self.team, bus.owner),
                lease=aon_lease,
                on_deliver=lambda status, _id: self.record_status(status),
                payloads=(TaskStatus,),  # the team's statuses, nothing else
            )
        bus.subscribe(TOPIC_TASK_STATUS, self._on_status)
        bus.subscribe(TOPIC_POSE, BatchHandler(self._on_poses))
        self.commands = CommandInbox(
            bus, incarnation, lambda: command_team(self.team, self.agent_id), self.on_command
        )

    @property
    def agent_id(self) -> str:
        return self.bus.owner

    @property
    def settled(self) -> bool:
        """No acknowledged message still in flight at the assigner."""
        return (self.aon is None or not self.aon.pending_ids()) and self.commands.settled()

    def set_time(self, now: float) -> None:
        """The time of the coming delivery and step (see TaskExecutor.set_time)."""
        self._now = now

    def step(self, now: float) -> None:
        self._now = now
        self.commands.step(now)
        if self.aon is not None:
            self.aon.step(now)
            if now >= self._next_heartbeat:
                # Robots prove they are alive with their poses; the assigner has none,
                # and without this AON's lease would give up on it between statuses.
                self._next_heartbeat = now + HEARTBEAT_PERIOD
                self._seq += 1
                self.bus.publish(
                    TOPIC_HEARTBEAT,
                    Heartbeat(
                        sender=self.agent_id, incarnation=self.incarnation, seq=self._seq, stamp=now
                    ),
                )
        if not self.assigned:
            for robot in self.team:
                self._seq += 1
                self.bus.publish(
                    TOPIC_ASSIGNMENT,
                    Assignment(
                        sender=self.agent_id,
                        incarnation=self.incarnation,
                        seq=self._seq,
                        stamp=now,
                        robot=robot,
                        tasks=tuple(self.agenda[robot]),
                        team=self.team,
                    ),
                )
            self.assigned = True

    def record_status(self, status: TaskStatus) -> None:
        """Record a task status, whichever layer delivered it (plain topic or AON). A
        robot reports only its own work: a status naming another robot than its sender
        is refused (counted in ``refused``), so that a member cannot be credited with,
        or rob another of, a task."""
        if status.robot != status.sender:
            self.refused["status of another robot"] += 1
            return
        self.received[TOPIC_TASK_STATUS] += 1
        self.status_log.append((self._now, status))
        if status.state is TaskState.SUCCESS:
            self.success_received.setdefault((status.task_id, status.robot), self._now)

    def on_command(self, command: OperatorCommand) -> None:
        """An operator's command: a task reassigned or added changes whose SUCCESS the
        assigner expects (what failed tasks are counted against)."""
        task = command.task
        if task is None or command.robot not in self.agenda:
            return
        if command.command is CommandKind.CONFIRM:
            # Known done by the operator's word, not by the robot's status: kept apart,
            # so failed tasks still count what communication lost.
            self.confirmed.setdefault((task.task_id, command.robot), self._now)
            return
        if command.command is CommandKind.REASSIGN and command.former in self.agenda:
            former = self.agenda[command.former]
            self.agenda[command.former] = [t for t in former if t.task_id != task.task_id]
        adds = command.command in (CommandKind.REASSIGN, CommandKind.ADD)
        if adds and task not in self.agenda[command.robot]:
            self.agenda[command.robot].append(task)

    def failed(self) -> list[tuple[str, str]]:
        """(task_id, robot) pairs whose completion never reached the assigner."""
        return [
            (task.task_id, robot)
            for robot in self.team
            for task in self.agenda[robot]
            if (task.task_id, robot) not in self.success_received
        ]

    def failed_tasks(self) -> list[str]:
        """Task ids with at least one uncommunicated completion."""
        seen: dict[str, None] = {}
        for task_id, _ in self.failed():
            seen.setdefault(task_id, None)
        return list(seen)

    def _on_status(self, message: Message) -> None:
        assert isinstance(message, TaskStatus)
        self.record_status(message)

    def _on_poses(self, messages: Sequence[Message]) -> None:
        """Poses that reached the assigner, in order (one, or a step's batch): counted,
        and each a sign of life to AON."""
        self.received[TOPIC_POSE] += len(messages)
        if self.aon is not None:
            for message in messages:
                self.aon.heard_from(message.sender, self._now)
