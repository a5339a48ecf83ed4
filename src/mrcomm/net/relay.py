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

**Store and forward** (``relay_store``, on top of relaying): a robot also keeps every
task status it has had — its own and those it received first — and sends them all again
(as relayed copies, each within the hop limit) whenever a robot comes into its range.
Relaying alone is immediate: a status published where no mate can hear it is never
passed on; stored, it travels with the robots until it meets the assigner (epidemic
routing, as delay-tolerant networks do). AON messages are not stored: AON re-sends them
by itself.

What relaying did is counted per node (:meth:`Relay.stats`): copies it passed on,
copies it received first, duplicates it dropped, and the hop counts of the messages it
received first.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

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

    relay_store: bool = Field(
        False,
        description="with relay: robots keep the task statuses they have had and send "
        "them again whenever a robot comes into range (store and forward)",
    )

    def hop_limit(self) -> int:
        """The hop limit when relaying is on, else 0."""
        return self.relay_hops if self.relay else 0


@dataclass(frozen=True)
class RelayOptions:
    """What a bus relays: the hop limit (0: nothing) and store and forward. The bus
    (in-process or Zenoh) takes them from the run's network parameters
    (:func:`relay_options`); the network model itself knows nothing of relaying."""

    hops: int = 0
    store: bool = False


def relay_options(params: BaseModel) -> RelayOptions:
    """The relaying a network model's parameters ask for (none for a model without
    relaying options)."""
    if not isinstance(params, RelayParams):
        return RelayOptions()
    return RelayOptions(params.hop_limit(), params.relay and params.relay_store)


Key = tuple[str, str, int, int]


class Relay:
    """Which node has had which relayed message, and what relaying did."""

    def __init__(
        self, ids: Sequence[str], relayers: Sequence[int], hops: int, store: bool = False
    ) -> None:
        """``ids``: the network's nodes; ``relayers``: the indices of those that relay
        (the robots); ``hops``: the hop limit (at least 2); ``store``: store and
        forward task statuses."""
        self.ids = tuple(ids)
        self.relayers = frozenset(relayers)
        self.hops = hops
        #: Per node, the statuses it keeps to send again: key -> (topic, message, links
        #: crossed when it got it; 0: its own). None: no store and forward.
        self.store: list[dict[Key, tuple[str, Message, int]]] | None = (
            [{} for _ in self.ids] if store else None
        )
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
        key = self.key(topic, message)
        self._had[node].add(key)
        self._keep(node, key, topic, message, 0)

    def _keep(self, node: int, key: Key, topic: str, message: Message, hop: int) -> None:
        if self.store is not None and topic == TOPIC_TASK_STATUS and node in self.relayers:
            self.store[node][key] = (topic, message, hop)

    def on_links(
        self, before: Sequence[Sequence[bool]], now: Sequence[Sequence[bool]]
    ) -> list[tuple[int, str, Message, int]]:
        """Store and forward: the copies robots send because a node came into their
        range between ``before`` and ``now`` — (relayer, topic, message, links crossed
        before this send), each stored status whose copy stays within the hop limit."""
        assert self.store is not None
        out: list[tuple[int, str, Message, int]] = []
        for node in sorted(self.relayers):
            kept = self.store[node]
            if not kept:
                continue
            row, old = now[node], before[node]
            if not any(row[j] and not old[j] for j in range(len(row)) if j != node):
                continue
            for topic, message, hop in kept.values():
                if hop + 1 <= self.hops:
                    self.passed_on[node] += 1
                    out.append((node, topic, message, hop))
        return out

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
        self._keep(node, key, topic, message, hop)
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


def make_relay(nodes: Sequence[str], robots: int, options: RelayOptions) -> Relay | None:
    """The relay of a network whose first ``robots`` nodes are the robots (the ones
    that relay), or None when the hop limit is 0 (relaying off)."""
    return Relay(nodes, range(robots), options.hops, options.store) if options.hops else None
