"""KernelLinks' decisions and rules without a kernel: which pairs get which drop
probability, the nftables script, and reading the counters back."""

from __future__ import annotations

import json

import numpy as np

from mrcomm.live.kernel_links import Emulation, KernelLinks
from mrcomm.net.links import LinkState


def state(connected: list[list[bool]]) -> LinkState:
    n = len(connected)
    ids = ("robot_1", "robot_2", "robot_3", "assigner")[:n]
    zeros = np.zeros((n, n))
    return LinkState(ids, zeros, None, None, zeros.astype(bool), np.array(connected))


EMULATION = Emulation(
    "hub",
    {"robot_1": "10.0.0.1", "robot_2": "10.0.0.2", "robot_3": "10.0.0.3", "assigner": "10.0.0.2"},
)


def test_decisions_follow_range_and_spl() -> None:
    links = KernelLinks(EMULATION, spl=25.0, write=lambda *a, **k: None)
    connected = [
        [True, True, False, True],
        [True, True, True, True],
        [False, True, True, True],
        [True, True, True, True],
    ]
    decided = links.permille(state(connected))
    # The assigner shares robot_2's process: its links are robot_2's.
    assert decided == {
        ("robot_1", "robot_2"): 250,
        ("robot_1", "robot_3"): 1000,
        ("robot_2", "robot_1"): 250,
        ("robot_2", "robot_3"): 250,
        ("robot_3", "robot_1"): 1000,
        ("robot_3", "robot_2"): 250,
    }
    script = links.script(decided)
    assert "ip saddr 10.0.0.1 ip daddr 10.0.0.3 counter counter drop" in script
    assert "ip saddr 10.0.0.1 ip daddr 10.0.0.2 counter numgen random mod 1000 < 250" in script
    assert "hook forward" in script and script.startswith("table bridge mrcomm_links\n")
    no_loss = KernelLinks(EMULATION, spl=0.0, write=lambda *a, **k: None)
    plain = no_loss.script({("robot_1", "robot_2"): 0})
    assert "ip saddr 10.0.0.1 ip daddr 10.0.0.2 counter\n" in plain and "drop" not in plain


def test_counts_are_read_and_journalled() -> None:
    def expr(saddr: str, daddr: str, counters: list[int]) -> dict[str, object]:
        matches = [
            {"match": {"op": "==", "left": {}, "right": saddr}},
            {"match": {"op": "==", "left": {}, "right": daddr}},
        ]
        return {"rule": {"expr": matches + [{"counter": {"packets": c}} for c in counters]}}

    listing = {"nftables": [{"table": {}}, expr("10.0.0.1", "10.0.0.3", [40, 40]),
                            expr("10.0.0.3", "10.0.0.1", [12])]}  # fmt: skip
    calls: list[tuple[str, ...]] = []

    def tool(*args: str, stdin: str | None = None) -> str:
        calls.append(args)
        return json.dumps(listing) if "-j" in args else ""

    lines: list[dict[str, object]] = []
    links = KernelLinks(
        EMULATION, 0.0, lambda kind, **data: lines.append({"k": kind, **data}), tool
    )
    assert links.counts() == {("robot_1", "robot_3"): (40, 40), ("robot_3", "robot_1"): (12, 0)}
    connected = [[True, True, False], [True, True, True], [False, True, True]]
    links.update(state(connected), now=1.0)
    assert not links.due(1.4) and links.due(1.5)  # 2 Hz of mission time
    links.update(state(connected), now=1.5)
    assert lines[0]["t0"] == 1.0 and lines[0]["t1"] == 1.5
    assert ["robot_1", "robot_3", 1000, 40, 40] in lines[0]["pairs"]
    assert all(call[:4] == ("ip", "netns", "exec", "hub") for call in calls)


def test_radio_packet_error_adds_to_spl() -> None:
    """With the radio, a link in range drops its packet error on top of the SPL (as
    independent losses); below the sensitivity everything."""
    links = KernelLinks(
        EMULATION, spl=10.0, write=lambda *a, **k: None, packet_error=lambda dbm: 0.5
    )
    connected = [[True, True, False], [True, True, True], [False, True, True]]
    linked = state(connected)
    radio = LinkState(
        linked.ids, linked.distance, None, None, linked.warning, linked.connected,
        np.full((3, 3), -80.0),
    )  # fmt: skip
    decided = links.permille(radio)
    assert decided[("robot_1", "robot_2")] == 550  # 1 - 0.9 * 0.5
    assert decided[("robot_1", "robot_3")] == 1000


def test_radio_packet_error_follows_power() -> None:
    from mrcomm.live.kernel_links import PACKET_BYTES
    from mrcomm.net.radio.model import RadioNetwork
    from mrcomm.run.config import make_config
    from mrcomm.run.resources import ScenarioResources
    from mrcomm.run.wiring import build_network

    from .helpers import S1

    config = make_config(None, scenario=S1, network="radio")
    network = build_network(config, ScenarioResources.load(S1))
    assert isinstance(network, RadioNetwork)
    channel = network.channel(("robot_1", "robot_2"))
    bits = channel.bits_of(PACKET_BYTES)
    errors = [channel.mean_error(dbm, bits) for dbm in (-60.0, -80.0, -88.0, -92.0)]
    assert errors == sorted(errors) and errors[0] < 0.01 and errors[-1] > errors[0]
    assert channel.mean_error(float("nan"), bits) == 0.0
