"""The operator: a human supervising the team, as a member of the team on the bus.

Like the task assigner, the operator is an agent behind the Bus port, so it is subject
to the same network as everyone (placed with the task assigner at its base station, or
carried by a robot). It knows what reaches it — each robot's last pose and when it was
sent, the task statuses it hears (plain, or read from the team's AON traffic it
overhears) — and nothing else, and it acts through commands
(:class:`~mrcomm.messaging.messages.OperatorCommand`) sent with AON to the robots and
the task assigner (:mod:`mrcomm.agents.commands`): reassign a task, send a robot back to
do a task again (its status was lost), confirm a task it saw done (its status never
arrived), add a task, pause or resume a robot.

:meth:`Operator.command` is what a console (or a script) calls; every command is
logged with its time, the members known to have it (its acknowledgements) and when AON
finished it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import msgspec

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.agents.assignment import round_robin
from mrcomm.agents.commands import COMMAND_LEASE, OPERATOR_ID, command_team
from mrcomm.messaging.aon import AonEndpoint, FinishReport, MessageId
from mrcomm.messaging.messages import (
    TOPIC_AON,
    TOPIC_COMMAND,
    TOPIC_POSE,
    TOPIC_TASK_STATUS,
    AonMsg,
    CommandKind,
    Message,
    OperatorCommand,
    PoseMsg,
    TaskSpec,
    TaskState,
    TaskStatus,
)
from mrcomm.ports import Bus

#: The commands that need a task, and those that need none.
TASK_COMMANDS = frozenset(
    {CommandKind.REASSIGN, CommandKind.REDO, CommandKind.ADD, CommandKind.CONFIRM}
)


@dataclass
class CommandRecord:
    """One command as the operator sent it and saw it travel."""

    time: float
    command: CommandKind
    robot: str
    task_id: str
    former: str
    msg_id: MessageId
    #: Members known to have it (the operator included), as last learnt.
    acknowledged: tuple[str, ...] = ()
    finished_at: float | None = None
    left_out: tuple[str, ...] = ()
    #: An added task's position.
    where: tuple[float, float] | None = None

    def as_dict(self) -> dict[str, Any]:
        where = {"x": self.where[0], "y": self.where[1]} if self.where is not None else {}
        return {
            **where,
            "time": self.time,
            "command": str(self.command),
            "robot": self.robot,
            "task_id": self.task_id,
            "former": self.former,
            "acknowledged": list(self.acknowledged),
            "finished_at": self.finished_at,
            "left_out": list(self.left_out),
        }


@dataclass
class KnownPose:
    x: float
    y: float
    theta: float
    stamp: float  # when the robot sent it (mission clock)
    role: str = ""  # its team role, as its pose says (LF: leader, follower, ...)
    leader: str = ""  # the robot it follows


@dataclass
class Ownership:
    """Who does which task, as the operator knows it: the first assignment (the same
    round-robin the task assigner applies) changed by the operator's own commands."""

    tasks: dict[str, TaskSpec]
    owner: dict[str, str]
    robots: tuple[str, ...]
    added: set[str] = field(default_factory=set)
    #: The behaviour lets an operator move and add tasks (its spec says).
    reassignable: bool = True

    @classmethod
    def initial(
        cls, robots: Sequence[str], tasks: Sequence[TaskSpec], reassignable: bool = True
    ) -> Ownership:
        agenda = round_robin(tasks, robots)
        owner = {t.task_id: robot for robot, ts in agenda.items() for t in ts}
        return cls({t.task_id: t for t in tasks}, owner, tuple(robots), reassignable=reassignable)

    def resolve(
        self,
        kind: CommandKind | str,
        robot: str = "",
        task_id: str = "",
        where: tuple[float, float] | None = None,
    ) -> OperatorCommand:
        """The command for ``kind`` (a header-less draft: sender and sequence are the
        operator's), checked against what the operator knows, and applied to the
        ownership. Raises ValueError with a one-line reason."""
        try:
            kind = CommandKind(kind)
        except ValueError:
            names = ", ".join(k.value for k in CommandKind)
            raise ValueError(f"unknown command {kind!r}; choose from {names}") from None
        task: TaskSpec | None = None
        former = ""
        if kind in (CommandKind.REASSIGN, CommandKind.ADD) and not self.reassignable:
            raise ValueError(f"the behaviour does not accept {kind} (its spec says so)")
        if kind in TASK_COMMANDS and not task_id:
            raise ValueError(f"{kind} needs a task")
        if kind is CommandKind.ADD:
            if task_id in self.tasks:
                raise ValueError(f"task {task_id!r} exists already")
            if where is None or not all(math.isfinite(v) for v in where):
                raise ValueError("add needs the task's position x, y")
            task = TaskSpec(task_id=task_id, type="added", x=where[0], y=where[1])
        elif kind in TASK_COMMANDS:
            if task_id not in self.tasks:
                raise ValueError(f"unknown task {task_id!r}")
            task = self.tasks[task_id]
            former = self.owner[task_id]
            robot = robot or former  # redo: the robot that did it
        if robot not in self.robots:
            raise ValueError(f"unknown robot {robot!r}; the team is {', '.join(self.robots)}")
        if kind is CommandKind.REASSIGN:
            if robot == former:
                raise ValueError(f"task {task_id!r} is {robot}'s already")
            self.owner[task_id] = robot
        elif kind is CommandKind.ADD:
            assert task is not None
            self.tasks[task_id] = task
            self.owner[task_id] = robot
            self.added.add(task_id)
        elif kind in (CommandKind.REDO, CommandKind.CONFIRM):
            former = ""  # nothing is taken from anyone
        return OperatorCommand(
            sender=OPERATOR_ID, incarnation=0, seq=0, stamp=0.0,
            command=kind, robot=robot, task=task, former=former,
        )  # fmt: skip


class Operator:
    """The operator's agent (see the module docstring)."""

    def __init__(
        self,
        bus: Bus,
        robots: Sequence[str],
        tasks: Sequence[TaskSpec],
        *,
        incarnation: int = 1,
        reassignable: bool = True,
    ) -> None:
        """``reassignable``: the behaviour accepts reassign and add (its spec)."""
        self.bus = bus
        self.robots = tuple(robots)
        self.incarnation = incarnation
        self.ownership = Ownership.initial(self.robots, tasks, reassignable)
        #: Each robot's last pose that reached the operator.
        self.poses: dict[str, KnownPose] = {}
        #: (task id, robot) -> when the operator first heard its SUCCESS.
        self.successes: dict[tuple[str, str], float] = {}
        self.log: list[CommandRecord] = []
        self._by_id: dict[MessageId, CommandRecord] = {}
        self._seq = 0
        self._now = 0.0
        self.aon = AonEndpoint(
            bus,
            OPERATOR_ID,
            incarnation,
            command_team(self.robots, ASSIGNER_ID),
            lease=COMMAND_LEASE,
            on_deliver=lambda _payload, _id: None,  # the operator's own commands only
            on_finished=self._finished,
            topic=TOPIC_COMMAND,
        )
        bus.subscribe(TOPIC_POSE, self._on_pose)
        bus.subscribe(TOPIC_TASK_STATUS, self._on_status)
        bus.subscribe(TOPIC_AON, self._on_team_aon)

    @property
    def agent_id(self) -> str:
        return self.bus.owner

    @property
    def settled(self) -> bool:
        """Every command the operator sent has finished (or left members out)."""
        return not self.aon.pending_ids()

    def set_time(self, now: float) -> None:
        self._now = now

    def step(self, now: float) -> None:
        self._now = now
        self.aon.step(now)
        for record in self.log:
            if record.finished_at is None:
                holders = self.aon.holders(record.msg_id)
                if holders is not None:
                    record.acknowledged = holders

    def command(
        self,
        kind: CommandKind | str,
        robot: str = "",
        task_id: str = "",
        where: tuple[float, float] | None = None,
    ) -> CommandRecord:
        """Send one command now (raises ValueError, sending nothing, when it makes no
        sense to the operator: unknown task or robot, a task reassigned to its owner)."""
        draft = self.ownership.resolve(kind, robot, task_id, where)
        self._seq += 1
        message = msgspec.structs.replace(
            draft, incarnation=self.incarnation, seq=self._seq, stamp=self._now
        )
        msg_id = self.aon.send(message, self._now)
        record = CommandRecord(
            self._now, draft.command, draft.robot,
            draft.task.task_id if draft.task is not None else "", draft.former, msg_id,
            acknowledged=(OPERATOR_ID,),
            where=(draft.task.x, draft.task.y) if draft.command is CommandKind.ADD and draft.task
            else None,
        )  # fmt: skip
        self.log.append(record)
        self._by_id[msg_id] = record
        return record

    def lost_statuses(self) -> list[str]:
        """Tasks whose SUCCESS the operator has not heard from their owner (what it
        might send a robot back for)."""
        own = self.ownership.owner
        return [t for t, robot in own.items() if (t, robot) not in self.successes]

    def summary(self) -> dict[str, Any]:
        return {
            "commands": [r.as_dict() for r in self.log],
            "successes_heard": len(self.successes),
            "robots_seen": sorted(self.poses),
        }

    # -- what reaches the operator -------------------------------------------------------
    def _on_pose(self, message: Message) -> None:
        assert isinstance(message, PoseMsg)
        self.poses[message.sender] = KnownPose(
            message.x, message.y, message.theta, message.stamp, message.role, message.leader
        )
        self.aon.heard_from(message.sender, self._now)

    def _on_status(self, message: Message) -> None:
        assert isinstance(message, TaskStatus)
        self._heard_status(message)

    def _on_team_aon(self, message: Message) -> None:
        """The team's AON traffic carries statuses: read them, without taking part."""
        if isinstance(message, AonMsg):
            for entry in message.entries:
                if isinstance(entry.payload, TaskStatus):
                    self._heard_status(entry.payload)

    def _heard_status(self, status: TaskStatus) -> None:
        if status.state is TaskState.SUCCESS:
            self.successes.setdefault((status.task_id, status.robot), self._now)

    def _finished(self, msg_id: MessageId, report: FinishReport) -> None:
        record = self._by_id.get(msg_id)
        if record is None:
            return
        record.finished_at = report.finished
        record.left_out = report.left_out
        members = command_team(self.robots, ASSIGNER_ID)
        record.acknowledged = tuple(m for m in members if m not in report.left_out)


def apply_commands(
    agenda: dict[str, list[TaskSpec]], commands: Sequence[Mapping[str, Any]]
) -> dict[str, list[TaskSpec]]:
    """The task assigner's agenda after the operator's recorded commands (reassign
    moves a task to its new owner, add gives one a new task): what a run's failed tasks
    are counted against, rebuilt from the record (live mode's collection)."""
    out = {robot: list(tasks) for robot, tasks in agenda.items()}
    by_id = {t.task_id: t for tasks in out.values() for t in tasks}
    for c in commands:
        robot, task_id = c["robot"], c["task_id"]
        if c["command"] == CommandKind.REASSIGN and task_id in by_id:
            out[c["former"]] = [t for t in out[c["former"]] if t.task_id != task_id]
            out[robot].append(by_id[task_id])
        elif c["command"] == CommandKind.ADD and "x" in c:
            task = TaskSpec(task_id=task_id, type="added", x=c["x"], y=c["y"])
            by_id[task_id] = task
            out[robot].append(task)
    return out
