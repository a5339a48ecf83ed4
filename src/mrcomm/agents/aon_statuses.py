"""Task statuses sent with AON (acknowledged All-Or-Nothing messaging): the part of an
executor that LF and the other behaviours whose statuses must reach every member share.

Once its assignment arrives the executor opens an :class:`AonEndpoint` over the team and
the task assigner; the statuses in :attr:`AonStatuses.AON_STATES` go with it (re-sent
until every member has them), the others are plain publications. Poses and heartbeats
count as a member being heard (AON's lease); the endpoint is stepped before every state
handler; the executor is done only when nothing it sent is still pending."""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.executor import TaskExecutor
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.agents.report_tour import ReportTour, report_places
from mrcomm.messaging.aon import AonEndpoint, MessageId
from mrcomm.messaging.messages import (
    TOPIC_HEARTBEAT,
    TOPIC_TASK_STATUS,
    Assignment,
    Message,
    TaskState,
    TaskStatus,
)
from mrcomm.ports import NavStatus

#: A robot's last known position counts as where the assigner on it is for this long (s).
HOST_FRESH = 30.0
#: A member silent this long is left out of pending messages, unless the behaviour's
#: parameters say otherwise (``aon_lease``).
DEFAULT_AON_LEASE = 60.0


class AonStatuses(TaskExecutor):
    """An executor whose statuses go with AON (see the module docstring)."""

    uses_aon = True
    #: The statuses sent with AON.
    AON_STATES: ClassVar[frozenset[TaskState]] = frozenset({TaskState.SUCCESS})

    def __init__(self, context: AgentContext, params: ExecutorParams) -> None:
        """The context's ``assigner``: where the task assigner is (the scenario's), and
        ``assigner_home`` the start of the robot it runs on, so that a robot can bring
        it a status it missed."""
        self.aon: AonEndpoint | None = None
        self.report_tour = ReportTour()
        assigner = context.assigner
        self._assigner_host = (assigner.host or "") if assigner is not None else ""
        self._assigner_at = assigner.position if assigner is not None else None
        self.assigner_home = context.assigner_home
        super().__init__(context, params)
        self.bus.subscribe(TOPIC_HEARTBEAT, self._on_heartbeat)

    def aon_settled(self) -> bool:
        """Nothing this robot sent with AON is still pending."""
        return self.aon is None or not self.aon.pending_ids()

    def unreported(self) -> bool:
        """Something this robot sent with AON was finished without the task assigner
        (left out when its lease ran out) and has not reached it since."""
        if self.aon is None:
            return False
        aon = self.aon
        return any(
            msg_id[0] == self.robot_id and self._assigner_id not in (aon.holders(msg_id) or ())
            for msg_id in aon.left_out_ids()
        )

    def assigner_position(self) -> tuple[float, float] | None:
        """Where the task assigner is: its base station; or its robot's last known
        position while that is fresh (heard within ``HOST_FRESH`` s), else that robot's
        home, where it waits once its own work is done (None: virtual)."""
        host = self._assigner_host
        known = self.team_view.poses.get(host)
        if known is not None and self.team_view.age(host, self._now) <= HOST_FRESH:
            return (known.x, known.y)
        return self._assigner_at or self.assigner_home

    def hosts_assigner(self) -> bool:
        """This robot carries the task assigner."""
        return self.robot_id == self._assigner_host

    def report_target(self) -> tuple[float, float] | None:
        """Where to go next to bring the assigner a status it missed: the next place
        of the report tour (:mod:`mrcomm.agents.report_tour`)."""
        mates = {mate: (known.x, known.y) for mate, known in self.mates.items()}
        places, order = report_places(mates, self.team_view.heard, self.assigner_position())
        pose = self.base.pose
        failed = self.base.status is NavStatus.ABORTED
        return self.report_tour.target((pose.x, pose.y), places, order, self._now, failed=failed)

    def send_status(self, task_id: str, state: TaskState) -> None:
        status = self.status_message(task_id, state)
        if self.aon is None or state not in self.AON_STATES:
            self.bus.publish(TOPIC_TASK_STATUS, status)  # informational statuses: plain
            return
        self.aon.send(status, self._now)

    def rejoined(self) -> None:
        """AON brings the team what this robot completed while it was away."""

    def _on_aon_deliver(self, status: TaskStatus, msg_id: MessageId) -> None:
        self.on_team_status(status)

    def _on_poses(self, messages: Sequence[Message]) -> None:
        super()._on_poses(messages)
        if self.aon is not None:
            for message in messages:  # liveliness for the lease
                self.aon.heard_from(message.sender, self._now)

    def _on_heartbeat(self, message: Message) -> None:
        if self.aon is not None:
            self.aon.heard_from(message.sender, self._now)

    def _on_assignment(self, message: Message) -> None:
        first = self._t0 is None
        super()._on_assignment(message)
        if first and self._t0 is not None:
            assert isinstance(message, Assignment)
            self.aon = AonEndpoint(
                self.bus,
                self.robot_id,
                self.incarnation,
                (*message.team, message.sender),
                lease=getattr(self.params, "aon_lease", DEFAULT_AON_LEASE),
                on_deliver=self._on_aon_deliver,
                payloads=(TaskStatus,),  # the team's statuses, nothing else
            )

    def before_state_step(self) -> None:
        if self.aon is not None:
            self.aon.step(self._now)
