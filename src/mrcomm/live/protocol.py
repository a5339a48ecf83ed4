"""Messages between the live processes that are not agent traffic: the world's clock
tick (with every robot's base state), base commands, agent heartbeats and the
resynchronisation of a restarted robot. Keys live under ``mrcomm/<team>/``:

==============================  ===========================  ==================
key                             payload                      lane
==============================  ===========================  ==================
``world/tick``                  :class:`Tick`                best effort
``<robot>/base_cmd``            :class:`BaseCommand`         control (reliable)
``<agent>/agent_state``         :class:`AgentState`          control (reliable)
``<agent>/sync_request``        :class:`SyncRequest`         control (reliable)
``<agent>/sync_reply``          :class:`SyncReply`           control (reliable)
==============================  ===========================  ==================
"""

from __future__ import annotations

from typing import Any

import msgspec

from mrcomm.messaging.messages import Assignment

WORLD_ID = "world"
CH_TICK = "tick"
CH_BASE_CMD = "base_cmd"
CH_AGENT_STATE = "agent_state"
CH_SYNC_REQUEST = "sync_request"
CH_SYNC_REPLY = "sync_reply"
#: The world answers queries on its ``roster`` key: who is present as it sees them.
CH_ROSTER = "roster"


class BaseState(msgspec.Struct, frozen=True, array_like=True):
    """One robot's base as its navigation stack reports it (estimate, not truth)."""

    robot: str
    status: str  # NavStatus value
    x: float
    y: float
    theta: float
    odometry: float
    v: float
    #: The last command applied: (agent incarnation, command sequence).
    incarnation: int
    ack: int


class Tick(msgspec.Struct, frozen=True):
    """The shared clock: simulated time ``time`` and every base's state at that time.
    ``end`` is set once the mission is over (``end_time`` is when it ended).
    ``mission``: the mission's identity (8 bytes), which an agent started without one
    adopts from its first tick."""

    time: float
    speed: float
    states: tuple[BaseState, ...]
    end: bool = False
    end_time: float = 0.0
    timed_out: bool = False
    mission: bytes = b""


class BaseCommand(msgspec.Struct, frozen=True):
    """Agent -> world: ``goto`` (x, y) or ``cancel`` for ``robot``'s base."""

    robot: str
    incarnation: int
    seq: int
    kind: str
    x: float = 0.0
    y: float = 0.0


class AgentState(msgspec.Struct, frozen=True):
    """Agent process heartbeat: ready (joined the team), done (nothing left to do) and,
    for a process hosting the task assigner, whether it has settled."""

    agent: str
    incarnation: int
    ready: bool
    done: bool
    hosted: tuple[str, ...] = ()
    settled: bool = True
    time: float = 0.0
    #: Fingerprint of the run configuration (every process must run the same one).
    config_crc: int = 0


class SyncRequest(msgspec.Struct, frozen=True):
    """A (re)started robot asks the team what it knows."""

    robot: str
    incarnation: int


class SyncReply(msgspec.Struct, frozen=True):
    """What the replying process knows: completed (task_id, robot) pairs, and, from the
    assigner's host, the robot's assignment."""

    sender: str
    to: str
    to_incarnation: int
    done: tuple[tuple[str, str], ...] = ()
    assignment: Assignment | None = None


class Roster(msgspec.Struct, frozen=True):
    """The world's answer to a joining agent: every member's live incarnations as the
    world sees their liveliness tokens. Every agent is connected to the world, so this
    is the one view that does not wait for the joining peer's own links to the others
    (Zenoh peers learn of each other by gossip and do not forward each other's tokens)."""

    present: dict[str, tuple[int, ...]]


def encoder() -> msgspec.msgpack.Encoder:
    return msgspec.msgpack.Encoder()


def decoder_of(kind: type[Any]) -> Any:
    """``bytes -> kind`` for :meth:`ZenohNode.listen`."""
    return msgspec.msgpack.Decoder(kind).decode


def roster_of(answers: list[bytes]) -> dict[str, tuple[int, ...]]:
    """Every incarnation the :class:`Roster` answers name, per member (an answer that
    does not decode names none)."""
    present: dict[str, set[int]] = {}
    decode = decoder_of(Roster)
    for answer in answers:
        try:
            roster = decode(answer)
        except (msgspec.DecodeError, msgspec.ValidationError):
            continue
        for agent, incarnations in roster.present.items():
            present.setdefault(agent, set()).update(incarnations)
    return {agent: tuple(sorted(i)) for agent, i in present.items()}
