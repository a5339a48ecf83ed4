"""Multi-hop relaying (the network models' ``relay`` option): robots pass on the team's
task statuses and AON traffic they hear to those they can hear, so that a chain of
robots carries a status to a task assigner out of direct range.

The rules, the same for every behaviour (relaying belongs to the network, not to the
agents, which see only the messages that reach them):

* relayed topics: task statuses and AON messages (:data:`RELAYED_TOPICS`); poses and
  LF's role messages are not (they are only worth their freshness);
* a message is identified by its topic and header (origin, incarnation, sequence
  number); a relayed copy is handed to a node's agents only if the node has not had
  that message yet — by the original publication, or an earlier copy — and dropped as
  a *duplicate* otherwise. Original publications are handed over as always (an AON
  re-send is an original: its receivers must see it to answer it);
* a robot passes on, once, each message it received first, while the copy it sends
  would have crossed at most ``hops`` links (the hop limit; the original publication's
  delivery crosses 1); a task assigner does not relay;
* a copy is sent from the relaying robot: the network decides its delivery on that
  robot's links and its receivers' losses, like any message it sends.

What relaying did is counted per node (:meth:`Relay.stats`): copies it passed on,
copies it received first, duplicates it dropped, and the hop counts of the messages it
received first.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from pydantic import BaseModel, ConfigDict, Field

from mrcomm.messaging.messages import Message
from mrcomm.messaging.topics import TOPIC_AON, TOPIC_TASK_STATUS

#: The topics relayed.
RELAYED_TOPICS = frozenset({TOPIC_TASK_STATUS, TOPIC_AON})


class RelayParams(BaseModel):
    """The relaying options of the network models that can cut links (``ah``, ``radio``)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    relay: bool = Field(
        False, description="robots relay task statuses and AON traffic to those they can hear"
    )
    relay_hops: int = Field(
        4,
        ge=2,
        le=32,
        description="hop limit: the most links a relayed message may cross",
        json_schema_extra={"unit": "links"},
    )

    def hop_limit(self) -> int:
        """The hop limit when relaying is on, else 0."""
        return self.relay_hops if self.relay else 0


Key = tuple[str, str, int, int]


class Relay:
    """Which node has had which relayed message, and what relaying did."""

    def __init__(self, ids: Sequence[str], relayers: Sequence[int], hops: int) -> None:
        """``ids``: the network's nodes; ``relayers``: the indices of those that relay
        (the robots); ``hops``: the hop limit (at least 2)."""
        self.ids = tuple(ids)
        self.relayers = frozenset(relayers)
        self.hops = hops
        self._had: list[set[Key]] = [set() for _ in self.ids]
        self.passed_on = [0] * len(self.ids)
        self.received_copies = [0] * len(self.ids)
        self.duplicates = [0] * len(self.ids)
        self.hop_counts: list[Counter[int]] = [Counter() for _ in self.ids]

    @staticmethod
    def relays(topic: str) -> bool:
        return topic in RELAYED_TOPICS

    @staticmethod
    def key(topic: str, message: Message) -> Key:
        return (topic, message.sender, message.incarnation, message.seq)

    def published(self, node: int, topic: str, message: Message) -> None:
        """``node`` published ``message``: it has it (no copy of it is handed back)."""
        self._had[node].add(self.key(topic, message))

    def receive(self, node: int, topic: str, message: Message, hop: int, copy: bool) -> bool:
        """``message`` reached ``node`` after crossing ``hop`` links (``copy``: relayed).
        Whether its agents get it: always for an original, for a copy only if the node
        has not had the message yet."""
        key = self.key(topic, message)
        had = self._had[node]
        if key in had:
            if copy:
                self.duplicates[node] += 1
                return False
            return True
        had.add(key)
        self.hop_counts[node][hop] += 1
        if copy:
            self.received_copies[node] += 1
        return True

    def passes_on(self, node: int, hop: int) -> bool:
        """Whether ``node`` relays a message it just received first after ``hop``
        links: it is a robot and its copy would cross at most the hop limit."""
        if node in self.relayers and hop + 1 <= self.hops:
            self.passed_on[node] += 1
            return True
        return False

    def stats(self) -> dict[str, dict[str, int | dict[str, int]]]:
        """Per node: copies passed on, copies received first, duplicates dropped, and
        how many relayed-topic messages it received first after each hop count."""
        return {
            node: {
                "passed_on": self.passed_on[i],
                "received_copies": self.received_copies[i],
                "duplicates": self.duplicates[i],
                "hops": {str(h): n for h, n in sorted(self.hop_counts[i].items())},
            }
            for i, node in enumerate(self.ids)
        }


def make_relay(nodes: Sequence[str], robots: int, hops: int) -> Relay | None:
    """The relay of a network whose first ``robots`` nodes are the robots (the ones
    that relay), or None when the hop limit is 0 (relaying off)."""
    return Relay(nodes, range(robots), hops) if hops else None
