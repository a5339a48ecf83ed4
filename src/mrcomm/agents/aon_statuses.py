"""Task statuses sent with AON (acknowledged All-Or-Nothing messaging): a part an
executor holds when its behaviour's statuses must reach every member (LF, serried).

A behaviour asks for it in one line (``Statuses = AonStatuses``; the runtime then makes
one per executor, ``executor.statuses``, and ``uses_aon`` is true). Once its
assignment arrives the part opens an :class:`AonEndpoint` over the team and the task
assigner; the statuses in ``AON_STATES`` go with it (re-sent until every member has
them), the others are plain publications. Poses and heartbeats count as a member being
heard (AON's lease); the endpoint is stepped before every state handler; a behaviour
holding it is done only when nothing it sent is still pending (:meth:`settled`). It
also knows what the task assigner missed (:meth:`unreported`), where the assigner is
(:meth:`assigner_position`) and where to look for it next (:meth:`report_target`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from mrcomm.agents.behaviour import AgentContext
from mrcomm.agents.report_tour import ReportTour, report_places
from mrcomm.messaging.aon import AonEndpoint, MessageId
from mrcomm.messaging.messages import (
    TOPIC_TASK_STATUS,
    Assignment,
    Message,
    TaskState,
    TaskStatus,
)
from mrcomm.ports import NavStatus

if TYPE_CHECKING:
    from mrcomm.agents.runtime import ExecutorRuntime

#: A robot's last known position counts as where the assigner on it is for this long (s).
HOST_FRESH = 30.0
#: A member silent this long is left out of pending messages, unless the behaviour's
#: parameters say otherwise (``aon_lease``).
DEFAULT_AON_LEASE = 60.0


def lease_of(params: object) -> float | None:
    """The team's AON lease: a behaviour's ``aon_lease`` parameter, else the default."""
    lease: float | None = getattr(params, "aon_lease", DEFAULT_AON_LEASE)
    return lease


class AonStatuses:
    """The AON part of one executor (see the module docstring)."""

    #: The statuses sent with AON (a behaviour may widen it: serried sends the end of
    #: each agenda with AON too).
    AON_STATES: frozenset[TaskState] = frozenset({TaskState.SUCCESS})

    def __init__(self, executor: ExecutorRuntime, context: AgentContext) -> None:
        """The context's ``assigner``: where the task assigner is (the scenario's), and
        ``assigner_home`` the start of the robot it runs on, so that a robot can bring
        it a status it missed."""
        self.executor = executor
        self.aon: AonEndpoint | None = None
        self.report_tour = ReportTour()
        assigner = context.assigner
        self._assigner_host = (assigner.host or "") if assigner is not None else ""
        self._assigner_at = assigner.position if assigner is not None else None
        self.assigner_home = context.assigner_home

    # -- what the runtime tells it ----------------------------------------------------
    def assigned(self, message: Assignment) -> None:
        """The executor's assignment arrived: open the endpoint over the team."""
        e = self.executor
        self.aon = AonEndpoint(
            e.bus,
            e.robot_id,
            e.incarnation,
            (*message.team, message.sender),
            lease=lease_of(e.params),
            on_deliver=self._on_aon_deliver,
            payloads=(TaskStatus,),  # the team's statuses, nothing else
        )

    def heard(self, messages: Sequence[Message]) -> None:
        """Messages that say their senders are alive (poses, heartbeats): AON's lease."""
        if self.aon is not None:
            now = self.executor.now
            for message in messages:
                self.aon.heard_from(message.sender, now)

    def step(self, now: float) -> None:
        """Before every state handler: AON's re-sends, replies and lease."""
        if self.aon is not None:
            self.aon.step(now)

    def send(self, task_id: str, state: TaskState) -> None:
        """Send a status: with AON when it is one of ``AON_STATES``, else plainly."""
        status = self.executor.status_message(task_id, state)
        if self.aon is None or state not in self.AON_STATES:
            self.executor.bus.publish(TOPIC_TASK_STATUS, status)  # informational: plain
            return
        self.aon.send(status, self.executor.now)

    def _on_aon_deliver(self, status: TaskStatus, msg_id: MessageId) -> None:
        self.executor.on_team_status(status)

    # -- what a behaviour asks of it ----------------------------------------------------
    def settled(self) -> bool:
        """Nothing this robot sent with AON is still pending."""
        return self.aon is None or not self.aon.pending_ids()

    def unreported(self) -> bool:
        """Something this robot sent with AON was finished without the task assigner
        (left out when its lease ran out) and has not reached it since."""
        if self.aon is None:
            return False
        aon, e = self.aon, self.executor
        return any(
            msg_id[0] == e.robot_id and e.assigner_id not in (aon.holders(msg_id) or ())
            for msg_id in aon.left_out_ids()
        )

    def assigner_position(self) -> tuple[float, float] | None:
        """Where the task assigner is: its base station; or its robot's last known
        position while that is fresh (heard within ``HOST_FRESH`` s), else that robot's
        home, where it waits once its own work is done (None: virtual)."""
        host, view = self._assigner_host, self.executor.team_view
        known = view.poses.get(host)
        if known is not None and view.age(host, self.executor.now) <= HOST_FRESH:
            return (known.x, known.y)
        return self._assigner_at or self.assigner_home

    @property
    def assigner_host(self) -> str:
        """The robot carrying the task assigner ("": a base station or virtual)."""
        return self._assigner_host

    def hosts_assigner(self) -> bool:
        """This robot carries the task assigner."""
        return self.executor.robot_id == self._assigner_host

    def report_target(self) -> tuple[float, float] | None:
        """Where to go next to bring the assigner a status it missed: the next place
        of the report tour (:mod:`mrcomm.agents.report_tour`)."""
        e = self.executor
        mates = {mate: (known.x, known.y) for mate, known in e.mates.items()}
        places, order = report_places(mates, e.team_view.heard, self.assigner_position())
        pose = e.base.pose
        failed = e.base.status is NavStatus.ABORTED
        return self.report_tour.target((pose.x, pose.y), places, order, e.now, failed=failed)
