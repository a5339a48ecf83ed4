"""Messages on one topic decided as a batch (large teams) make the same decisions, the
same counts and the same handler calls as one message at a time."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

from mrcomm.agents.team_view import TeamView
from mrcomm.messaging import latest as latest_module
from mrcomm.messaging.latest import KEEP_LATEST_FROM
from mrcomm.messaging.messages import Message, PoseMsg
from mrcomm.net import inprocess
from mrcomm.net.delivery import DeliveryPolicy, LossStream
from mrcomm.net.inprocess import InProcessNetwork
from mrcomm.ports import Addressed, BatchHandler, KeepLatest
from mrcomm.run.config import make_config
from mrcomm.sim.mission import Mission
from tests.golden.golden import comparable

ROOT = Path(__file__).resolve().parents[2]


def test_take_gives_the_draws_in_order() -> None:
    one, many = LossStream(np.random.default_rng(5)), LossStream(np.random.default_rng(5))
    singles = [one.draw() for _ in range(4000)]
    taken = [many.draw(), *many.take(1500).tolist(), *many.take(0).tolist()]
    taken += many.take(1499).tolist()
    # A batch refilled by take() and then read by draw() (its list made lazily).
    taken += [*many.take(100).tolist(), *(many.draw() for _ in range(900))]
    assert taken == singles


def _network(ids: list[str], batch_from: int) -> InProcessNetwork:
    """A team at SPL 40, each agent's loss stream seeded by its place; messages decided
    as a batch from ``batch_from`` receivers."""
    net = InProcessNetwork(
        ids,
        policy=DeliveryPolicy(40.0),
        loss_rngs={a: np.random.default_rng(i) for i, a in enumerate(ids)},
    )
    net.batch_from = batch_from
    return net


def _pose(sender: str, k: int) -> PoseMsg:
    return PoseMsg(sender=sender, incarnation=1, seq=k, stamp=0.1 * k, x=float(k), y=0.0, theta=0.0)


def _deliveries(
    batch_from: int, taking_many: frozenset[str] = frozenset()
) -> tuple[list[tuple[str, str, int]], dict, list[int]]:
    """Twelve agents, a ragged link matrix, SPL 40: who got which pose, in order; the
    agents in ``taking_many`` subscribe with a BatchHandler (the sizes of its calls are
    returned too)."""
    ids = [f"r{i}" for i in range(12)]
    net = _network(ids, batch_from)
    got: list[tuple[str, str, int]] = []
    calls: list[int] = []

    def take(agent: str, messages: Sequence[Message]) -> None:
        calls.append(len(messages))
        got.extend((agent, m.sender, round(m.x)) for m in messages)  # type: ignore[attr-defined]

    for a in ids:
        if a in taking_many:
            net.endpoint(a).subscribe("pose", BatchHandler(lambda ms, a=a: take(a, ms)))
            continue
        net.endpoint(a).subscribe(
            "pose",
            lambda m, a=a: got.append((a, m.sender, round(m.x))),  # type: ignore[misc]
        )
    rng = np.random.default_rng(9)
    for step in range(30):
        net.set_connected(rng.random((12, 12)) < 0.7)
        for k, a in enumerate(ids):
            if (step + k) % 2 == 0:
                net.endpoint(a).publish("pose", _pose(a, step * 100 + k))
        net.deliver(0.1 * step)
    return got, net.counts_by_agent(), calls


def test_batched_and_single_deliveries_agree() -> None:
    batched, batched_counts, _ = _deliveries(batch_from=0)
    single, single_counts, _ = _deliveries(batch_from=10**6)
    assert batched == single
    assert batched_counts == single_counts
    counts = batched_counts["r3"]["pose"]
    assert counts["dropped_loss"] > 0 and counts["dropped_range"] > 0 and counts["received"] > 0


@pytest.mark.parametrize(("scenario", "behaviour"), [("s1.yaml", "lf"), ("s2/s2.yaml", "nb")])
def test_missions_are_the_same_batched_or_not(scenario: str, behaviour: str) -> None:
    config = make_config(
        None,
        scenario=ROOT / "data" / "scenarios" / scenario,
        network="ah",
        threshold="slt",
        behaviour=behaviour,
        spl=25,
        seed=3,
        max_time=90,
    )
    results = []
    for batch_from in (0, 10**6):
        mission = Mission(config)
        mission.network.batch_from = batch_from
        results.append(comparable(mission.run()))
    assert results[0] == results[1]


def _per_agent(got: list[tuple[str, str, int]], agent: str) -> list[tuple[str, str, int]]:
    return [entry for entry in got if entry[0] == agent]


@pytest.mark.parametrize("block_entries", [1 << 20, 13])
def test_a_batch_handler_gets_each_receivers_poses_of_a_step_in_one_call(
    block_entries: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Half the agents take their poses in batches: each agent still gets the same poses
    in the same order; the plain handlers are called in the same order as before; a
    batch handler is called once per step in the batched path, per pose otherwise.
    Also when a batch's receivers are decided and handed over a few at a time (as in a
    team of thousands)."""
    monkeypatch.setattr(latest_module, "_BLOCK_ENTRIES", block_entries)
    many = frozenset(f"r{i}" for i in range(0, 12, 2))
    single, counts, _ = _deliveries(batch_from=10**6)
    for batch_from in (0, 10**6):
        got, got_counts, calls = _deliveries(batch_from, many)
        assert got_counts == counts
        for agent in (f"r{i}" for i in range(12)):
            assert _per_agent(got, agent) == _per_agent(single, agent)
        plain = [entry for entry in got if entry[0] not in many]
        assert plain == [entry for entry in single if entry[0] not in many]
        heard = sum(1 for entry in single if entry[0] in many)
        assert sum(calls) == heard
        if batch_from == 0:
            assert len(calls) <= 30 * len(many) < heard  # one call per receiver and step
        else:
            assert set(calls) == {1}  # one message at a time


def _views(batch_from: int, keep_from: int, monkeypatch: pytest.MonkeyPatch) -> list[TeamView]:
    """A team of KEEP_LATEST_FROM + 6 agents hearing each other's poses in team views
    (subscribed as the runtime does) over a ragged link matrix at SPL 40; some steps
    have an agent publish twice. The bus keeps the latest poses for teams of at least
    ``keep_from`` endpoints."""
    monkeypatch.setattr(inprocess, "KEEP_LATEST_FROM", keep_from)
    ids = [f"r{i}" for i in range(KEEP_LATEST_FROM + 6)]
    net = _network(ids, batch_from)
    views = [TeamView() for _ in ids]
    now = [0.0]
    for a, view in zip(ids, views, strict=True):

        def hear(ms: Sequence[Message], view: TeamView = view, a: str = a) -> None:
            view.hear_all(ms, now[0], a)  # type: ignore[arg-type]

        net.endpoint(a).subscribe("pose", KeepLatest(hear, view.attach, ("x", "y")))
    rng = np.random.default_rng(9)
    for step in range(25):
        now[0] = 0.1 * step
        net.set_connected(rng.random((len(ids), len(ids))) < 0.7)
        for k, a in enumerate(ids):
            if (step + k) % 3 == 0:
                net.endpoint(a).publish("pose", _pose(a, step * 1000 + k))
        if step % 5 == 4:
            net.endpoint(ids[1]).publish("pose", _pose(ids[1], step * 1000 + 999))
        net.deliver(now[0])
    return views


@pytest.mark.parametrize("block_entries", [1 << 20, 29])
def test_the_bus_keeps_the_poses_each_view_would_hear(
    block_entries: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The bus's store of latest poses (written a step at a time, or message by message
    when a sender has two in a step or messages go one at a time) gives every view the
    poses, heard times and order of first hearing it gets hearing them itself; also a
    few receivers at a time."""
    monkeypatch.setattr(latest_module, "_BLOCK_ENTRIES", block_entries)
    heard_itself = _views(batch_from=0, keep_from=10**6, monkeypatch=monkeypatch)
    kept_in_steps = _views(batch_from=0, keep_from=1, monkeypatch=monkeypatch)
    kept_one_by_one = _views(batch_from=10**6, keep_from=1, monkeypatch=monkeypatch)
    assert all(v._table is None for v in heard_itself)
    assert all(v._table is not None for v in kept_in_steps + kept_one_by_one)
    for own, stepped, single in zip(heard_itself, kept_in_steps, kept_one_by_one, strict=True):
        assert list(stepped.poses.items()) == list(own.poses.items())
        assert list(single.poses.items()) == list(own.poses.items())
        assert list(stepped.heard.items()) == list(own.heard.items())
        assert list(single.heard.items()) == list(own.heard.items())
    assert sum(len(v.poses) for v in heard_itself) > 1000


def test_addressed_handlers_are_called_only_for_their_own_messages() -> None:
    """Handlers that act only on messages addressed to them (an assignment's robot; here
    a pose's sender) act on the same messages in the same order whether the bus calls
    them for every message (one at a time) or only for theirs (a batch): 12 agents,
    each acting on one mate's poses, over a ragged link matrix at SPL 40."""

    def run(batch_from: int) -> tuple[list[tuple[str, str, int]], int]:
        ids = [f"r{i}" for i in range(12)]
        net = _network(ids, batch_from)
        acted: list[tuple[str, str, int]] = []
        calls = [0]

        class Counted(Addressed):
            def __call__(self, message: Message) -> None:
                calls[0] += 1
                super().__call__(message)

        for i, a in enumerate(ids):
            mate = ids[(i + 1) % len(ids)]
            act = lambda m, a=a: acted.append((a, m.sender, round(m.x)))  # type: ignore[misc]  # noqa: E731
            net.endpoint(a).subscribe("pose", Counted(act, "sender", mate))
        rng = np.random.default_rng(9)
        for step in range(30):
            net.set_connected(rng.random((12, 12)) < 0.7)
            for k, a in enumerate(ids):
                if (step + k) % 2 == 0:
                    net.endpoint(a).publish("pose", _pose(a, step * 100 + k))
            net.deliver(0.1 * step)
        return acted, calls[0]

    one_by_one, every_call = run(batch_from=10**6)
    batched, own_calls = run(batch_from=0)
    assert batched == one_by_one and len(batched) > 50
    assert own_calls == len(batched) < every_call / 5  # called only where it acts
