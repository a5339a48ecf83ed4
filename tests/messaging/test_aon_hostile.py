"""AON against a hostile member: what it takes is bounded, what it takes is authored by
its origin, and the team's own messages still go through a flood.

The rogue here is a member of the team (it holds a member's certificate, so the bus
edge lets its publications in under its own name): it publishes AON messages by hand.
"""

from __future__ import annotations

from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.messaging import aon
from mrcomm.messaging.aon import AonEndpoint
from mrcomm.messaging.aon_state import TeamIndex
from mrcomm.messaging.messages import (
    TOPIC_AON,
    AonEntry,
    AonMsg,
    CommandKind,
    OperatorCommand,
    TaskState,
    TaskStatus,
)
from tests.messaging.aon_team import AonTeam
from tests.messaging.fakenet import FakeNet

TEAM = ("r0", "r1", "rogue")


def status(sender: str, robot: str, seq: int = 0) -> TaskStatus:
    return TaskStatus(sender=sender, incarnation=0, seq=seq, stamp=0.0, robot=robot,
                      task_id=f"t{seq}", state=TaskState.SUCCESS)  # fmt: skip


def entry(origin: str, seq: int, payload: object, incarnation: int = 0) -> AonEntry:
    none = TeamIndex(TEAM).encode(0)
    return AonEntry(origin, incarnation, seq, none, none, payload=payload)  # type: ignore[arg-type]


def publication(entries: list[AonEntry], seq: int = 0) -> AonMsg:
    return AonMsg(sender="rogue", incarnation=0, seq=seq, stamp=0.0,
                  team_crc=TeamIndex(TEAM).crc, entries=tuple(entries))  # fmt: skip


def receiver(**options: object) -> tuple[AonEndpoint, list[object], FakeNet]:
    net = FakeNet(list(TEAM), seed=1)
    got: list[object] = []
    endpoint = AonEndpoint(
        net.buses["r0"], "r0", 0, TEAM, on_deliver=lambda p, _id: got.append(p), **options
    )  # type: ignore[arg-type]
    endpoint.step(0.0)
    return endpoint, got, net


def test_a_payload_is_taken_only_from_its_author() -> None:
    endpoint, got, _ = receiver()
    endpoint.receive(publication([
        entry("rogue", 0, status("rogue", "r1")),  # a status of another robot
        entry("r1", 0, status("rogue", "rogue")),  # a payload not of its origin
        entry("r1", 1, status("r1", "r1", 1)),  # relayed faithfully: taken
    ]))  # fmt: skip
    assert got == [status("r1", "r1", 1)]
    assert endpoint.refused == {"payload not authored by its origin": 2}


def test_only_the_operator_commands() -> None:
    pause = OperatorCommand(sender="rogue", incarnation=0, seq=0, stamp=0.0,
                            command=CommandKind.PAUSE, robot="r1")  # fmt: skip
    endpoint, got, _ = receiver(origins=frozenset({OPERATOR_ID}), payloads=(OperatorCommand,))
    endpoint.receive(
        publication([entry("rogue", 0, pause), entry("rogue", 1, status("rogue", "rogue", 1))])
    )
    assert got == []
    assert endpoint.refused == {"origin may not send on this topic": 2}
    statuses, got, _ = receiver(payloads=(TaskStatus,))
    statuses.receive(publication([entry("rogue", 0, pause)]))
    assert got == [] and statuses.refused == {"payload of the wrong type": 1}


def test_numbers_far_ahead_and_many_incarnations_are_refused() -> None:
    endpoint, _, _ = receiver()
    endpoint.receive(publication([entry("rogue", aon.MAX_SEQ_AHEAD, status("rogue", "rogue"))]))
    assert endpoint.refused == {"sequence number out of range": 1}
    for inc in range(1, aon.MAX_INCARNATIONS + 3):  # finished: remembered per incarnation
        endpoint._remember(("rogue", inc, 0))
    assert sum(1 for sender, _ in endpoint._records if sender == "rogue") == aon.MAX_INCARNATIONS
    endpoint.receive(publication([entry("rogue", 5, status("rogue", "rogue", 5), incarnation=1)]))
    assert endpoint.refused["incarnation out of range"] == 1


def test_a_flood_fills_only_the_flooders_share_and_the_team_still_talks() -> None:
    """63,800 messages from one member once grew every robot past 700 MB and made
    their own publications too large to send."""
    net = FakeNet(list(TEAM), seed=2)
    team = AonTeam(net)  # every member runs AON; the rogue also publishes by hand
    honest = team.endpoints["r0"]
    flood = [entry("rogue", seq, status("rogue", "rogue", seq)) for seq in range(1000)]
    for k in range(0, len(flood), 50):
        honest.receive(publication(flood[k : k + 50], seq=k))
    assert honest.memory()["states"] == aon.MAX_INTRODUCED
    assert honest.refused == {"member over its share of unfinished messages": 1000 - 256}
    published: list[int] = []
    bus = net.buses["r0"]
    original = bus.publish

    def counting(topic: str, message: object) -> None:
        if topic == TOPIC_AON:
            published.append(len(message.entries))  # type: ignore[attr-defined]
        original(topic, message)  # type: ignore[arg-type]

    bus.publish = counting  # type: ignore[method-assign]
    mid = team.send("r1", "task-9")
    net.run(5.0, stop=lambda: mid in team.delivered["r0"])
    assert team.delivered["r0"][mid] == 1  # the team's own message got through
    assert published and max(published) <= aon.MAX_ENTRIES  # none oversized
