"""Messages on one topic decided as a batch (large teams) make the same decisions, the
same counts and the same handler calls as one message at a time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrcomm.messaging.messages import PoseMsg
from mrcomm.net.delivery import DeliveryPolicy, LossStream
from mrcomm.net.inprocess import InProcessNetwork
from mrcomm.run.config import make_config
from mrcomm.sim.mission import Mission
from tests.golden.golden import comparable

ROOT = Path(__file__).resolve().parents[2]


def test_take_gives_the_draws_in_order() -> None:
    one, many = LossStream(np.random.default_rng(5)), LossStream(np.random.default_rng(5))
    singles = [one.draw() for _ in range(3000)]
    taken = [many.draw(), *many.take(1500).tolist(), *many.take(0).tolist()]
    taken += many.take(1499).tolist()
    assert taken == singles


def _pose(sender: str, k: int) -> PoseMsg:
    return PoseMsg(sender=sender, incarnation=1, seq=k, stamp=0.1 * k, x=float(k), y=0.0, theta=0.0)


def _deliveries(batch_from: int) -> tuple[list[tuple[str, str, int]], dict]:
    """Twelve agents, a ragged link matrix, SPL 40: who got which pose, in order."""
    ids = [f"r{i}" for i in range(12)]
    net = InProcessNetwork(
        ids,
        policy=DeliveryPolicy(40.0),
        loss_rngs={a: np.random.default_rng(i) for i, a in enumerate(ids)},
    )
    net.batch_from = batch_from
    got: list[tuple[str, str, int]] = []
    for a in ids:
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
    return got, net.counts_by_agent()


def test_batched_and_single_deliveries_agree() -> None:
    batched, batched_counts = _deliveries(batch_from=0)
    single, single_counts = _deliveries(batch_from=10**6)
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
