"""A process back from being away (``live.away``): it notices its own loop stood
still, or the clock's silence, and reopens its team session — a fresh Zenoh session
that declares again everything the old one had (``ZenohNode.reopen``)."""

from __future__ import annotations

from collections.abc import Callable

from mrcomm.live.away import REPORT_AFTER, AwayWatch
from mrcomm.messaging.topics import Lane
from mrcomm.net.zenoh_node import Incoming, Presence, ZenohNode

from .helpers import mesh_options, nodes, wait_for


def test_a_loop_or_a_clock_silent_past_the_lease_means_away() -> None:
    away = AwayWatch(lease=10.0)
    assert away.loop(100.0) is None  # the first pass: nothing to compare with
    assert away.loop(100.1) is None
    assert away.loop(109.9) is None  # 9.8 s: within the lease
    assert away.loop(140.0) == 140.0 - 109.9  # stopped for 30 s
    assert away.tick(100.0) is None
    assert away.tick(105.0) is None and not away.due(200.0)  # nothing scheduled
    assert away.tick(140.0) == 35.0
    first, second = (140.0 + after for after in REPORT_AFTER)
    assert not away.due(first - 0.1)
    assert away.due(first) and not away.due(first)  # each is due once
    assert not away.due(second - 0.1) and away.due(second + 5.0)
    assert not away.due(1e9)


def _wait(node: ZenohNode, what: str, until: Callable[[Incoming], bool]) -> Incoming:
    def step() -> Incoming | None:
        item = node.poll(0.05)
        return item if item is not None and until(item) else None

    return wait_for(step, 15.0, what)


def _sees(agent: str, alive: bool) -> Callable[[Incoming], bool]:
    return lambda item: item.channel == "presence" and item.value == Presence(agent, 1, alive)


def test_a_reopened_session_is_seen_again_and_keeps_every_declaration() -> None:
    """B reopens its session: A sees B's token go and come back, and samples flow
    both ways again through what B had declared (subscriber, publisher, token)."""
    with nodes(mesh_options(2, team="reopen")) as (a, b):
        for node, name in ((a, "a"), (b, "b")):
            node.listen("mrcomm/reopen/*/ping", "ping", bytes.decode)
            node.watch_presence()
            node.declare_alive(name, 1)
            node.prepare(node.key(name, "ping"), Lane.BEST_EFFORT)
        _wait(a, "a to see b", _sees("b", True))
        assert b.reopen() and b.reopened == 1
        _wait(a, "b's token to go", _sees("b", False))
        _wait(a, "b's token to come back", _sees("b", True))
        for sender, receiver, name in ((b, a, "b"), (a, b, "a")):

            def ping(sender: ZenohNode = sender, receiver: ZenohNode = receiver,
                     name: str = name) -> bool:  # fmt: skip
                sender.put(sender.key(name, "ping"), name.encode(), Lane.BEST_EFFORT)
                item = receiver.poll(0.05)
                return item is not None and item.channel == "ping" and item.value == name

            wait_for(ping, 15.0, f"{name}'s pings after the reopen")
