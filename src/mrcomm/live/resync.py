"""Resynchronising a robot that (re)joins a running mission (issue 7 §4).

A robot restarted after a crash has a new incarnation and has lost its state. It asks
the team (:class:`~mrcomm.live.protocol.SyncRequest`); every agent process answers
with the completed tasks it knows of, and the task assigner's host also with the
robot's assignment. Once the assignment is in and every live team process has
answered (or a short wait has passed), the robot learns the completions as team
statuses and receives its assignment *without the tasks the team already knows it
completed*, so it resumes its remaining agenda without redoing them. What it
completed but never managed to tell anyone is done again — the team cannot know it.

The same exchange covers a robot that missed the assignment at mission start, and
(:meth:`Resync.catch_up`) a robot back from being away with its state intact (its
process stopped, then continued): statuses its mates sent once while its links were
down never reached it — a task another one depends on would wait for ever. It asks the
same question and learns the completions it lacks as team statuses at once; its
assignment and everything else it knows stand.
"""

from __future__ import annotations

from collections.abc import Callable

from mrcomm.agents.assigner import ASSIGNER_ID, TaskAssigner
from mrcomm.agents.executor import TaskExecutor
from mrcomm.live.protocol import SyncReply, SyncRequest
from mrcomm.messaging.messages import TOPIC_ASSIGNMENT, Assignment, Message, TaskState, TaskStatus
from mrcomm.net.zenoh_bus import ZenohEndpoint

Pairs = set[tuple[str, str]]


def reply_for(
    request: SyncRequest,
    sender: str,
    executor: TaskExecutor | None,
    assigner: TaskAssigner | None,
    now: float,
) -> SyncReply:
    """What this process tells a robot that asks (``robot`` "" = completer unknown)."""
    done: Pairs = set()
    if executor is not None:
        done |= {(task_id, "") for task_id in executor.known_done}
    assignment: Assignment | None = None
    if assigner is not None:
        done |= set(assigner.success_received)
        if request.robot in assigner.agenda:
            assignment = Assignment(
                sender=ASSIGNER_ID,
                incarnation=assigner.incarnation,
                seq=0,
                stamp=now,
                robot=request.robot,
                tasks=tuple(assigner.agenda[request.robot]),
                team=assigner.team,
            )
    return SyncReply(sender, request.robot, request.incarnation, tuple(sorted(done)), assignment)


class Resync:
    """The (re)joining side: holds the assignment back until the team has answered."""

    def __init__(
        self,
        executor: TaskExecutor,
        endpoint: ZenohEndpoint,
        request: Callable[[], None],
        *,
        wait: float,
    ) -> None:
        self.executor = executor
        self.endpoint = endpoint
        self._request = request
        self._wait = wait
        self.active = False
        self.applied = False
        self.done: Pairs = set()
        self.replied: set[str] = set()
        self.assignment: Assignment | None = None
        self._deadline = 0.0
        self._next_request = 0.0
        self.skipped: list[str] = []
        self._catch_up_until = -1.0  # answers to a catch-up are taken until then

    def start(self, now: float) -> None:
        """Ask the team; hold any assignment until the answers are in."""
        if self.active or self.applied:
            return
        self.active = True
        self._deadline = now + self._wait
        self._next_request = now + self._wait
        self.endpoint.gate = self._gate
        self._request()

    def catch_up(self, now: float) -> None:
        """Back after being away (see the module docstring): ask the team what it
        completed; answers are learnt as they come, for the usual wait."""
        self._catch_up_until = now + self._wait
        self._request()

    def on_reply(self, reply: SyncReply, now: float) -> list[str]:
        """Take a team process's answer; returns the completed tasks a catch-up learnt
        from it (a resynchronisation applies them once every answer is in)."""
        if reply.to != self.executor.robot_id:
            return []
        if reply.to_incarnation != self.executor.incarnation:
            return []
        if not self.active:
            return self._learn(reply, now) if now <= self._catch_up_until else []
        self.replied.add(reply.sender)
        self.done |= set(reply.done)
        if reply.assignment is not None and self.assignment is None:
            self.assignment = reply.assignment
        return []

    def _learn(self, reply: SyncReply, now: float) -> list[str]:
        known = self.executor.known_done
        learnt = sorted({task_id for task_id, _ in reply.done if task_id not in known})
        for task_id, robot in sorted(reply.done):
            if task_id in learnt:
                self.executor.on_team_status(_success(task_id, robot, now))
        return learnt

    def step(self, now: float, alive: set[str]) -> bool:
        """Apply once ready; ``alive``: team processes present now. True when applied."""
        if not self.active:
            return False
        if self.assignment is None:
            if now >= self._next_request:
                self._next_request = now + self._wait
                self._request()  # the assigner's host may have been away: ask again
            return False
        if not (alive <= self.replied or now >= self._deadline):
            return False
        self._apply(now)
        return True

    def _gate(self, topic: str, message: Message) -> Message | None:
        if topic == TOPIC_ASSIGNMENT and isinstance(message, Assignment):
            if message.robot == self.executor.robot_id and self.assignment is None:
                self.assignment = message
            return None
        return message

    def _apply(self, now: float) -> None:
        assert self.assignment is not None
        me = self.executor.robot_id
        single = {t.task_id for t in self.assignment.tasks if t.num_robots == 1}
        mine_done = {t for t, robot in self.done if robot == me or (robot == "" and t in single)}
        for task_id, robot in sorted(self.done):
            self.executor.on_team_status(_success(task_id, robot, now))
        remaining = tuple(t for t in self.assignment.tasks if t.task_id not in mine_done)
        self.skipped = sorted(t.task_id for t in self.assignment.tasks if t.task_id in mine_done)
        filtered = Assignment(
            sender=self.assignment.sender,
            incarnation=self.assignment.incarnation,
            seq=self.assignment.seq,
            stamp=self.assignment.stamp,
            robot=self.assignment.robot,
            tasks=remaining,
            team=self.assignment.team,
        )
        self.active = False
        self.applied = True
        self.endpoint.gate = None
        self.endpoint.inject(TOPIC_ASSIGNMENT, filtered)


def _success(task_id: str, robot: str, now: float) -> TaskStatus:
    """A team status saying ``robot`` ("" = unknown) completed ``task_id``, as the
    team's answers report it (they carry no message of their own)."""
    return TaskStatus(
        sender=robot or ASSIGNER_ID,
        incarnation=0,
        seq=0,
        stamp=now,
        robot=robot,
        task_id=task_id,
        state=TaskState.SUCCESS,
    )
