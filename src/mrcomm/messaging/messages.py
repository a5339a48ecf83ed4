"""Typed messages shared by the agents and their wire encoding.

Every message carries the sender id, the sender's incarnation (new each time an agent
starts), a per-sender sequence number and the send time. Structs are msgspec-tagged so
one decoder reads any of them.
"""

from __future__ import annotations

from enum import StrEnum

import msgspec

from mrcomm.world.tasks import TaskSpec

__all__ = ["TaskSpec"]  # re-exported: the assignment message carries tasks

# Topic names (the key space in live mode is mrcomm/<team>/<robot>/<topic>).
TOPIC_ASSIGNMENT = "assignment"
TOPIC_POSE = "pose"
TOPIC_TASK_STATUS = "task_status"
TOPIC_UTILITY = "utility"
TOPIC_ROLE = "role"
TOPIC_RSSI = "rssi"
TOPIC_AON = "aon"
TOPIC_HEARTBEAT = "heartbeat"
TOPIC_RELAYED = "relayed"
TOPIC_COMMAND = "command"  # the operator's commands, with AON (messages: AonMsg)
# How the network treats each topic: mrcomm.messaging.topics.


class TaskState(StrEnum):
    ASSIGNED = "ASSIGNED"
    STARTED = "STARTED"
    SUCCESS = "SUCCESS"
    FAILED = "FAILED"
    DISCONNECT_ROLE = "DISCONNECT_ROLE"
    AGENDA_COMPLETE = "AGENDA_COMPLETE"


class Message(msgspec.Struct, frozen=True, tag=True, kw_only=True):
    """Common header of every message."""

    sender: str
    incarnation: int
    seq: int
    stamp: float


class Assignment(Message, frozen=True, tag="assignment"):
    """Assigner -> executor: the robot's agenda, the team, sent once at start."""

    robot: str
    tasks: tuple[TaskSpec, ...]
    team: tuple[str, ...]


class PoseMsg(Message, frozen=True, tag="pose"):
    """Position, heading and speed; ``goal_dist`` (m, -1 without a goal) lets team
    mates decide right of way at a near collision; ``role`` is the sender's team role
    (LF: na / assigning / leader / follower / regrouping; empty without roles) and
    ``leader`` the robot it follows (LF followers; empty otherwise)."""

    x: float
    y: float
    theta: float
    v: float = 0.0
    goal_dist: float = -1.0
    role: str = ""
    leader: str = ""

    @property
    def robot(self) -> str:
        """The robot this pose is of (its sender): a pose reads as a team mate's state."""
        return self.sender


class TaskStatus(Message, frozen=True, tag="task_status"):
    """A robot's report about one of its tasks (or about itself, for role events)."""

    robot: str
    task_id: str
    state: TaskState


class CommandKind(StrEnum):
    """What an operator can tell the team (:class:`OperatorCommand`)."""

    REASSIGN = "reassign"  # the task goes to ``robot`` (its former owner drops it)
    REDO = "redo"  # ``robot`` does the task again and reports it again (a lost status)
    ADD = "add"  # a new task for ``robot``
    PAUSE = "pause"  # ``robot`` stops where it is ...
    RESUME = "resume"  # ... and carries on
    CONFIRM = "confirm"  # the operator saw the task done (its status never arrived)


class OperatorCommand(Message, frozen=True, tag="command"):
    """Operator -> team: one command, sent with AON to every robot and the task
    assigner (topic ``TOPIC_COMMAND``); each acts on the part that concerns it.
    ``robot``: the robot it is for; ``task``: the task concerned (reassign, redo, add);
    ``former``: a reassigned task's former owner."""

    command: CommandKind
    robot: str
    task: TaskSpec | None = None
    former: str = ""


class AonEntry(msgspec.Struct, frozen=True, array_like=True):
    """One message's AON state as its publisher knows it (see messaging.aon).

    ``have``/``recv`` are member bitmaps (little-endian bytes, members sorted by id): who
    is known to have the message, who is known to have set *received*. ``ask`` requests
    a reply from any member that knows more. ``payload`` is omitted once all have it.
    """

    sender: str
    incarnation: int
    seq: int
    have: bytes
    recv: bytes
    ask: bool = False
    payload: TaskStatus | OperatorCommand | None = None


class AonMsg(Message, frozen=True, tag="aon"):
    """An AON publication: the publisher's knowledge of several messages at once."""

    team_crc: int
    entries: tuple[AonEntry, ...] = ()


class UtilityMsg(Message, frozen=True, tag="utility"):
    round: int
    utility: float


class RoleMsg(Message, frozen=True, tag="role"):
    round: int
    role: str
    leader: str


class Heartbeat(Message, frozen=True, tag="heartbeat"):
    """I am alive (1 Hz)."""


class RssiMsg(Message, frozen=True, tag="rssi"):
    """Pulse -> its robot: measured RSSI (dBm) of one peer."""

    robot: str
    peer: str
    rssi: float


class RelayedMsg(Message, frozen=True, tag="relayed"):
    """A copy of a team mate's message passed on by the robot that sends this (live
    mode's multi-hop relaying; ``mrcomm.net.relay``): the message's topic, the links it
    will have crossed on arrival, and the message itself, encoded."""

    topic: str
    hop: int
    payload: bytes


AnyMessage = (
    Assignment
    | PoseMsg
    | TaskStatus
    | UtilityMsg
    | RoleMsg
    | RssiMsg
    | AonMsg
    | Heartbeat
    | RelayedMsg
)

_encoder = msgspec.msgpack.Encoder()
_decoder = msgspec.msgpack.Decoder(AnyMessage)


def encode(message: Message) -> bytes:
    """Compact binary wire form (msgpack)."""
    return _encoder.encode(message)


def decode(data: bytes) -> Message:
    """Inverse of :func:`encode`; raises ``msgspec.DecodeError`` on bad input."""
    return _decoder.decode(data)
