"""The one table of topics: what each carries and how the network treats it.

Both buses (in-process for simulation, Zenoh for live mode) read this table: which
topics simulated packet loss applies to, which are exempt from every perturbation, the
message type each carries and, in live mode, the transport lane it travels on.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from mrcomm.messaging.messages import (
    TOPIC_AON,
    TOPIC_ASSIGNMENT,
    TOPIC_COMMAND,
    TOPIC_HEARTBEAT,
    TOPIC_POSE,
    TOPIC_RELAYED,
    TOPIC_ROLE,
    TOPIC_RSSI,
    TOPIC_TASK_STATUS,
    TOPIC_UTILITY,
    AonMsg,
    Assignment,
    Heartbeat,
    Message,
    PoseMsg,
    RelayedMsg,
    RoleMsg,
    RssiMsg,
    TaskStatus,
    UtilityMsg,
)


class Lane(Enum):
    """Quality of service of a publication in live mode."""

    BEST_EFFORT = "best_effort"  # pose, RSSI: newest wins, dropped under congestion
    STATUS = "status"  # task status, AON: reliable, blocking, own priority
    CONTROL = "control"  # assignment, roles, base commands: reliable, blocking


@dataclass(frozen=True)
class Topic:
    name: str
    message: type[Message]
    #: Simulated packet loss (SPL) applies to it.
    lossy: bool
    #: No perturbation at all, not even the range cut (all agents start with perfect
    #: communication, so the task assignment always arrives).
    exempt: bool
    lane: Lane
    #: An agent declares its publisher up front (live mode).
    agent_publishes: bool = True
    #: Sent on a timer for as long as its sender runs (poses, presence, RSSI readings):
    #: one is nearly always in flight, so a mission's end does not wait for them.
    periodic: bool = False


TOPICS: dict[str, Topic] = {
    t.name: t
    for t in (
        Topic(TOPIC_ASSIGNMENT, Assignment, lossy=False, exempt=True, lane=Lane.CONTROL),
        Topic(TOPIC_POSE, PoseMsg, lossy=True, exempt=False, lane=Lane.BEST_EFFORT,
              periodic=True),
        Topic(TOPIC_TASK_STATUS, TaskStatus, lossy=True, exempt=False, lane=Lane.STATUS),
        # AON carries task statuses, so it is perturbed like them.
        Topic(TOPIC_AON, AonMsg, lossy=True, exempt=False, lane=Lane.STATUS),
        # The operator's commands, with AON among the robots, the assigner and the
        # operator: perturbed like statuses.
        Topic(TOPIC_COMMAND, AonMsg, lossy=True, exempt=False, lane=Lane.STATUS),
        # Live mode's relayed copies of statuses and AON messages (wrapped, so that
        # the relaying robot sends them under its own key), perturbed like them.
        Topic(TOPIC_RELAYED, RelayedMsg, lossy=True, exempt=False, lane=Lane.STATUS),
        Topic(TOPIC_UTILITY, UtilityMsg, lossy=False, exempt=False, lane=Lane.CONTROL),
        Topic(TOPIC_ROLE, RoleMsg, lossy=False, exempt=False, lane=Lane.CONTROL),
        # Presence of agents that publish no pose (the task assigner), like a Zenoh
        # liveliness token: not subject to loss, but cut by range like everything else.
        Topic(TOPIC_HEARTBEAT, Heartbeat, lossy=False, exempt=False, lane=Lane.CONTROL,
              agent_publishes=False, periodic=True),
        # Published by a robot's pulse process, never by an agent.
        Topic(TOPIC_RSSI, RssiMsg, lossy=False, exempt=False, lane=Lane.BEST_EFFORT,
              agent_publishes=False, periodic=True),
    )
}  # fmt: skip

LOSSY_TOPICS = frozenset(t.name for t in TOPICS.values() if t.lossy)
EXEMPT_TOPICS = frozenset(t.name for t in TOPICS.values() if t.exempt)
PERIODIC_TOPICS = frozenset(t.name for t in TOPICS.values() if t.periodic)
#: Every topic an agent may publish (their publishers are declared up front).
AGENT_TOPICS = tuple(t.name for t in TOPICS.values() if t.agent_publishes)


def lane_of(topic: str) -> Lane:
    known = TOPICS.get(topic)
    return known.lane if known is not None else Lane.CONTROL
