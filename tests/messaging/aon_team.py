"""Test harness: a team of AON endpoints on a :mod:`fakenet` network, with ground truth.

It records every delivery and every finish report and checks, as they happen, the
safety properties: no duplicate delivery, no payload mix-up, and no message reported
finished while a member not named as left out lacks it.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from mrcomm.messaging.aon import AonEndpoint, FinishReport, MessageId
from mrcomm.messaging.messages import TOPIC_AON, TaskState, TaskStatus
from tests.messaging.fakenet import FakeNet


class AonTeam:
    """Endpoints for ``team`` on ``net``; they are stepped by the net's ticks."""

    def __init__(
        self,
        net: FakeNet,
        team: Sequence[str] | None = None,
        *,
        lease: float | None = None,
        resend_period: float = 1.0 / 3.0,
        failsafe_timeout: float = 15.0,
        beacons: bool = False,
        label: str = "",
    ) -> None:
        self.net = net
        self.team = tuple(team if team is not None else net.members)
        self.lease = lease
        self.resend_period = resend_period
        self.failsafe_timeout = failsafe_timeout
        self.beacons = beacons
        self.label = label
        self.delivered: dict[str, Counter[MessageId]] = {m: Counter() for m in self.team}
        self.reports: dict[str, list[FinishReport]] = {m: [] for m in self.team}
        self.sent: dict[MessageId, TaskStatus] = {}
        self.violations: list[str] = []
        self.endpoints: dict[str, AonEndpoint] = {}
        self.incarnations: dict[str, int] = {}
        for member in self.team:
            self.start(member, 0)
        net.steppers.append(self.step)

    def start(self, member: str, incarnation: int) -> AonEndpoint:
        """(Re)start a member's endpoint: a new process with a fresh state."""
        bus = self.net.buses[member]
        bus.handlers.pop(TOPIC_AON, None)
        self.delivered[member] = Counter()
        self.incarnations[member] = incarnation
        endpoint = AonEndpoint(
            bus,
            member,
            incarnation,
            self.team,
            resend_period=self.resend_period,
            failsafe_timeout=self.failsafe_timeout,
            lease=self.lease,
            on_deliver=lambda payload, mid: self._delivered(member, payload, mid),
            on_finished=lambda mid, report: self._finished(member, mid, report),
        )
        self.endpoints[member] = endpoint
        return endpoint

    def step(self, now: float) -> None:
        if self.beacons:
            self._beacon(now)
        for endpoint in self.endpoints.values():
            endpoint.step(now)

    def _beacon(self, now: float) -> None:
        """Other traffic (poses) each step: a peer that gets through is heard from."""
        n = len(self.team)
        draws = self.net.rng.random(n * n)
        for i, a in enumerate(self.team):
            for j, b in enumerate(self.team):
                if a == b or draws[i * n + j] < self.net.loss or self.net.blocked(a, b, now):
                    continue
                self.endpoints[a].heard_from(b, now)

    def send(self, member: str, task: str = "t") -> MessageId:
        endpoint = self.endpoints[member]
        payload = TaskStatus(
            sender=member,
            incarnation=endpoint.incarnation,
            seq=len(self.sent),
            stamp=self.net.now,
            robot=member,
            task_id=task,
            state=TaskState.SUCCESS,
        )
        msg_id = endpoint.send(payload, self.net.now)
        self.sent[msg_id] = payload
        return msg_id

    def has(self, member: str, msg_id: MessageId) -> bool:
        """Ground truth: the member's current incarnation holds the message."""
        own = msg_id[0] == member and msg_id[1] == self.incarnations[member]
        return own or self.delivered[member][msg_id] > 0

    # -- callbacks checking safety as it happens

    def _delivered(self, member: str, payload: TaskStatus, msg_id: MessageId) -> None:
        self.delivered[member][msg_id] += 1
        if self.delivered[member][msg_id] > 1:
            self.violations.append(f"{self.label}: {member} got {msg_id} twice")
        if self.sent.get(msg_id) != payload:
            self.violations.append(f"{self.label}: {member} got a wrong payload for {msg_id}")

    def _finished(self, member: str, msg_id: MessageId, report: FinishReport) -> None:
        self.reports[member].append(report)
        lacking = [m for m in self.team if m not in report.left_out and not self.has(m, msg_id)]
        if lacking:
            self.violations.append(
                f"{self.label}: {member} reported {msg_id} finished at {self.net.now:.1f}"
                f" but {lacking} lack it (left_out={report.left_out})"
            )

    # -- liveness

    def all_done(self) -> bool:
        """Every sent message finished and released at every member."""
        for endpoint in self.endpoints.values():
            if endpoint.memory()["states"]:
                return False
            if not all(endpoint.is_finished(mid) for mid in self.sent):
                return False
        return True
