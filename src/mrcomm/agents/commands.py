"""The operator's commands where they arrive: at every robot and at the task assigner.

Commands travel with AON on their own topic (``TOPIC_COMMAND``), among the robots, the
task assigner and the operator (the *command team*; the team's AON for statuses is
unchanged). An agent opens its command endpoint when the first command message reaches
it — until an operator speaks, nothing is sent and no run changes — and hands each
command, once, to its owner. What a command does is the owner's business: a robot
changes its agenda or pauses (:class:`~mrcomm.agents.executor.TaskExecutor`), the task
assigner moves the task in the agenda it counts failed tasks against.
"""

from __future__ import annotations

from collections.abc import Callable

from mrcomm.messaging.aon import AonEndpoint, MessageId
from mrcomm.messaging.messages import TOPIC_COMMAND, AonMsg, Message, OperatorCommand
from mrcomm.ports import Bus

#: The operator's member id in the command team.
OPERATOR_ID = "operator"
#: A command-team member silent this long no longer holds a command up.
COMMAND_LEASE = 60.0


def command_team(robots: tuple[str, ...], assigner: str) -> tuple[str, ...]:
    """Members of the command team: every robot, the task assigner, the operator."""
    return (*robots, assigner, OPERATOR_ID)


class CommandInbox:
    """One agent's end of the command team, opened on the first command message."""

    def __init__(
        self,
        bus: Bus,
        incarnation: int,
        team: Callable[[], tuple[str, ...] | None],
        on_command: Callable[[OperatorCommand], None],
    ) -> None:
        """``team``: the command team once the agent knows it (None before its
        assignment: a command before that is left to AON's re-sends)."""
        self._bus = bus
        self._incarnation = incarnation
        self._team = team
        self._on_command = on_command
        self.endpoint: AonEndpoint | None = None
        bus.subscribe(TOPIC_COMMAND, self._on_message)

    def _on_message(self, message: Message) -> None:
        if not isinstance(message, AonMsg):
            return
        if self.endpoint is None:
            team = self._team()
            if team is None:
                return
            self.endpoint = AonEndpoint(
                self._bus,
                self._bus.owner,
                self._incarnation,
                team,
                lease=COMMAND_LEASE,
                on_deliver=self._deliver,
                topic=TOPIC_COMMAND,
                subscribe=False,  # this inbox hands it every message, this one first
                origins=frozenset({OPERATOR_ID}),  # only the operator commands
                payloads=(OperatorCommand,),
            )
        self.endpoint.receive(message)

    def _deliver(self, payload: object, _id: MessageId) -> None:
        if isinstance(payload, OperatorCommand):
            self._on_command(payload)

    def step(self, now: float) -> None:
        if self.endpoint is not None:
            self.endpoint.step(now)

    def settled(self) -> bool:
        """Nothing this agent holds of the operator's commands is still pending."""
        return self.endpoint is None or not self.endpoint.pending_ids()
