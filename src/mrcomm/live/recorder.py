"""What an agent process records about its agents, as it goes (issue 7 §3): every
delivery decision (the message log), the task statuses the assigner received, AON
reports that left a silent member out, and periodic counts and AON statistics. The
journal format is described in :mod:`mrcomm.live.journal`."""

from __future__ import annotations

from collections import Counter
from typing import Any

from mrcomm.agents.assigner import ASSIGNER_ID, TaskAssigner
from mrcomm.agents.executor import TaskExecutor
from mrcomm.live.journal import OUTCOME_CODE, Journal
from mrcomm.messaging.aon import AonEndpoint
from mrcomm.messaging.messages import Message
from mrcomm.net.zenoh_bus import ZenohBus


def aon_of(executor: TaskExecutor | None) -> AonEndpoint | None:
    """The executor's AON endpoint, for behaviours that send statuses with AON."""
    aon = getattr(executor, "aon", None)
    return aon if isinstance(aon, AonEndpoint) else None


class AgentRecorder:
    """Writes one process's agents' records to its journal."""

    def __init__(
        self,
        journal: Journal,
        bus: ZenohBus,
        agent: str,
        executor: TaskExecutor | None,
        assigner: TaskAssigner | None,
    ) -> None:
        self.journal = journal
        self.bus = bus
        self.agent = agent
        self.executor = executor
        self.assigner = assigner
        self._status_logged = 0
        self._left_out_logged: set[Any] = set()
        self._left_out_reports = 0

    def delivery(
        self, now: float, topic: str, sender: str, receiver: str, message: Message, outcome: str
    ) -> None:
        """The bus's observer: one line per delivery decision."""
        self.journal.write(
            "msg",
            t=now,
            to=receiver,
            topic=topic,
            frm=sender,
            seq=message.seq,
            out=OUTCOME_CODE[outcome],
        )

    def receipts(self) -> None:
        """Task statuses the hosted assigner received since the last call."""
        if self.assigner is None:
            return
        log = self.assigner.status_log
        for t, status in log[self._status_logged :]:
            self.journal.write(
                "status_rx",
                time=t,
                task_id=status.task_id,
                robot=status.robot,
                state=status.state.value,
            )
        self._status_logged = len(log)

    def left_out(self, now: float, absent: list[str]) -> None:
        """Messages AON reported finished without a silent member (``absent``: the
        members whose liveliness token is gone, the ones it gave up waiting for)."""
        aon = aon_of(self.executor)
        if aon is None:
            return
        new = [m for m in aon.left_out_ids() if m not in self._left_out_logged]
        if not new:
            return
        self._left_out_logged.update(new)
        reports = aon.stats.left_out_reports
        if reports == self._left_out_reports:
            return  # gave up on a silent member's *received* flag only: nobody lacks it
        self._left_out_reports = reports
        for msg_id in new:
            self.journal.write("left_out", time=now, msg=list(msg_id), absent=absent)

    def aon_endpoints(self) -> dict[str, AonEndpoint]:
        out: dict[str, AonEndpoint] = {}
        aon = aon_of(self.executor)
        if aon is not None:
            out[self.agent] = aon
        if self.assigner is not None and self.assigner.aon is not None:
            out[ASSIGNER_ID] = self.assigner.aon
        return out

    def refusals(self) -> dict[str, int]:
        """Everything refused in this process so far, by cause."""
        causes = Counter(self.bus.node.refused)
        endpoints = list(self.aon_endpoints().values())
        for owner in (self.executor, self.assigner):
            inbox = getattr(owner, "commands", None)
            if inbox is not None and inbox.endpoint is not None:
                endpoints.append(inbox.endpoint)
        for endpoint in endpoints:
            causes.update({f"aon: {cause}": n for cause, n in endpoint.refused.items()})
        if self.assigner is not None:
            causes.update({f"assigner: {c}": n for c, n in self.assigner.refused.items()})
        return dict(causes)

    def counts(self) -> None:
        """Cumulative message counts and AON statistics (the last snapshot counts)."""
        self.journal.write("counts", agents=self.bus.counts_by_agent())
        relay = self.bus.relay_stats()
        if relay:
            self.journal.write("relay", agents=relay)
        # What peers sent that was refused (cumulative, by cause): at the bus edge, by
        # AON (a payload not of its author, a member over its share, ...) and by the
        # task assigner (a status of another robot).
        self.journal.write("refused", causes=self.refusals())
        for agent, aon in self.aon_endpoints().items():
            st = aon.stats
            self.journal.write(
                "aon",
                agent=agent,
                **st.counters(),
                pending=len(aon.pending_ids()),
                finish_times=list(st.finish_times.values()),
            )

    def final(self, max_lag: float) -> None:
        self.counts()
        latency = self.bus.pose_latency
        if latency:
            self.journal.write("pose_latency", samples=[round(x, 6) for x in latency])
        self.journal.write("lag", max_lag=round(max_lag, 6))
