"""The shared channel (net/radio/medium.py): carrier sense, backoff, collisions, hidden
terminals, the queue, and its results in a mission."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from mrcomm.net.radio.medium import Frame, SharedMedium
from mrcomm.net.radio.profile import RadioProfile, load_profile
from mrcomm.net.radio.reception import ber, per
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import run_mission
from tests.golden.golden import comparable

BITS = (150 + 64) * 8


def _profile(**update: object) -> RadioProfile:
    return load_profile("office-2.4ghz").model_copy(update=update)


def _medium(power: np.ndarray, profile: RadioProfile | None = None, seed: int = 0) -> SharedMedium:
    n = len(power)
    medium = SharedMedium(
        profile or _profile(), n, [np.random.default_rng([seed, i]) for i in range(n)]
    )
    p = power.astype(float).copy()
    np.fill_diagonal(p, np.nan)
    medium.set_power(p)
    return medium


def _all_in_range(n: int, dbm: float = -50.0) -> np.ndarray:
    return np.full((n, n), dbm)


def _at(medium: SharedMedium, sender: int, t: float) -> None:
    """A frame of ``sender`` arriving exactly at ``t`` (advancing to ``t`` right after
    the submission pins its arrival there; nothing has finished by then in these tests)."""
    assert medium.advance(t) == []
    medium.submit(sender, t, BITS, sender)
    assert medium.advance(t) == []


def test_a_frame_on_an_idle_channel_goes_at_once() -> None:
    medium = _medium(_all_in_range(2))
    _at(medium, 0, 0.010)
    (frame,) = medium.advance(0.1)
    assert frame.start == pytest.approx(0.010)
    assert frame.delay == pytest.approx(medium.airtime(BITS))
    assert frame.airtime == pytest.approx(192e-6 + BITS / 1e6)
    assert not frame.blocked[1] and not frame.chunk_mw.any()  # (0 was sending)


def test_a_sender_that_hears_the_air_busy_defers_and_backs_off() -> None:
    profile = _profile()
    medium = _medium(_all_in_range(2), profile)
    _at(medium, 0, 0.010)
    _at(medium, 1, 0.011)  # during the first frame
    first, second = medium.advance(0.1)
    difs = profile.sifs_s + 2 * profile.slot_s
    assert second.start >= first.end + difs - 1e-12
    slots = (second.start - first.end - difs) / profile.slot_s
    assert slots == pytest.approx(round(slots)) and 0 <= round(slots) <= profile.cw_min
    assert not first.blocked[1] and not second.blocked[0]
    assert not first.chunk_mw.any() and not second.chunk_mw.any()


def test_hidden_terminals_collide_at_the_node_between_them() -> None:
    """0 and 2 cannot hear each other; 1 hears both, 3 hears only 0."""
    power = np.array(
        [
            [0, -50, -200, -55],
            [-50, 0, -50, -200],
            [-200, -50, 0, -200],
            [-55, -200, -200, 0],
        ],
        dtype=float,
    )
    medium = _medium(power)
    _at(medium, 0, 0.010)
    _at(medium, 2, 0.011)  # 2 does not hear 0's frame: it sends at once
    first, second = medium.advance(0.1)
    assert second.start == pytest.approx(0.011)  # no deferral: hidden
    # 0's payload is cut where 2's frame starts: clear before, 2's power after.
    assert first.chunk_mw[:, 1] == pytest.approx([0.0, 10 ** (-50 / 10)])
    assert sum(first.chunk_bits) == pytest.approx(BITS)
    assert first.chunk_bits[0] == pytest.approx((0.011 - 0.010 - 192e-6) * 1e6)
    assert second.blocked[1]  # 1 was receiving 0's frame
    assert not first.blocked[3] and (first.chunk_mw[:, 3] < 1e-15).all()  # 3 is clear


def test_a_frame_meets_each_interferer_only_where_it_overlaps() -> None:
    """1 is locked on 0's frame; 2 and 3, hidden from 0 and from each other, send short
    frames one after the other during its payload, each as strong at 1 as 0's. The payload
    is judged chunk by chunk (as ns-3 does): each interfered chunk at 0 dB (DSSS survives
    it), never at the −3 dB of both interferers at once, which would lose about 1.4 %."""
    power = np.full((4, 4), -200.0)
    power[0, 1] = power[2, 1] = power[3, 1] = -50.0
    power[1, :] = -50.0
    profile = _profile(modulation="dsss", preamble_snr_db=4.0)
    medium = _medium(power, profile)
    short = 200
    ended: list[Frame] = []
    for sender, t, bits in ((0, 0.0100, BITS), (2, 0.0103, short), (3, 0.0110, short)):
        ended += medium.advance(t)
        medium.submit(sender, t, bits, sender)
        ended += medium.advance(t)
    frames = {f.sender: f for f in ended + medium.advance(0.1)}
    assert frames[2].start == 0.0103 and frames[3].start == 0.0110
    frame = frames[0]
    assert frames[2].blocked[1] and frames[3].blocked[1]  # 1 was locked on 0's
    # Payload from 10.192 ms: clear, 2's frame (392 µs), clear, 3's, clear (µs = bits).
    assert frame.chunk_bits == pytest.approx([108, 392, 308, 392, 512], abs=1e-6)
    mw = 10 ** (-50 / 10)
    assert frame.chunk_mw[:, 1] == pytest.approx([0.0, mw, 0.0, mw, 0.0])

    def ber_at(interference_mw: float) -> float:
        noise_mw = 10 ** (profile.noise_floor_dbm / 10)
        sinr_db = -50.0 - 10 * math.log10(noise_mw + interference_mw)
        return ber(sinr_db + profile.noise_floor_dbm, profile.noise_floor_dbm, profile, False)

    expected = 1 - (1 - ber_at(mw)) ** 784 * (1 - ber_at(0.0)) ** (BITS - 784)
    assert frame.shared[1] == pytest.approx(expected, rel=1e-6)
    assert frame.shared[1] < 1e-6
    assert per(ber_at(2 * mw), BITS) > 0.01  # the old rule: every overlap at once


def _together(medium: SharedMedium, senders: list[int], t: float) -> list[Frame]:
    """Frames of ``senders`` arriving in the same instant ``t`` on an idle channel."""
    medium.advance(t)
    for sender in senders:
        medium.submit(sender, t, BITS, sender)
    medium.advance(t)
    return medium.advance(t + 0.1)


def test_frames_that_start_in_one_slot_collide_and_the_strongest_is_taken() -> None:
    power = _all_in_range(3)
    power[0, 2], power[1, 2] = -40.0, -70.0
    medium = _medium(power, _profile(modulation="dsss", preamble_snr_db=4.0))
    a, b = _together(medium, [0, 1], 0.010)
    assert a.start == b.start
    frames = {f.sender: f for f in (a, b)}
    assert not frames[0].blocked[2] and frames[1].blocked[2]  # 2 locked on 0 (30 dB stronger)
    assert frames[0].blocked[1] and frames[1].blocked[0]  # each sender was transmitting


def test_a_preamble_below_its_sinr_is_not_detected() -> None:
    power = _all_in_range(3)  # equal powers: SINR 0 dB at the third node
    medium = _medium(power, _profile(modulation="dsss", preamble_snr_db=4.0))
    a, b = _together(medium, [0, 1], 0.010)
    assert a.start == b.start
    assert a.blocked[2] and b.blocked[2]


def test_saturated_senders_collide_as_often_as_bianchi_predicts() -> None:
    """n saturated senders, equal power, broadcast (the window never doubles): a frame
    escapes collision with probability (1 − τ)^(n−1), τ = 2 / (cw_min + 2). Bianchi's
    model has no EIFS (which favours the senders of a collision next): here EIFS = DIFS."""
    n = 10
    profile = _profile(sifs_s=0.0, ack_s=0.0)
    medium = _medium(_all_in_range(n), profile, seed=3)
    clean = total = 0
    for step in range(1, 31):
        t = step * 0.1
        for sender in range(n):
            while medium.queued(sender) < 50:
                medium.submit(sender, t - 0.1, BITS, None)
        for frame in medium.advance(t):
            if not frame.dropped:
                total += 1
                clean += not frame.chunk_mw.any()
    tau = 2.0 / (profile.cw_min + 2)
    assert total > 1000
    assert clean / total == pytest.approx((1 - tau) ** (n - 1), abs=0.04)


def test_the_queue_holds_at_most_max_queue_s_of_traffic() -> None:
    medium = _medium(_all_in_range(2), _profile(max_queue_s=0.05))
    for _ in range(200):
        medium.submit(0, 0.0, BITS, None)
    frames = medium.advance(0.0) + medium.advance(1.0)  # all arrive at 0
    sent = [f for f in frames if not f.dropped]
    dropped = [f for f in frames if f.dropped]
    assert len(sent) + len(dropped) == 200 and medium.pending() == 0
    assert all(f.start - f.submitted <= 0.05 + 1e-9 for f in sent)
    assert 20 <= len(sent) <= 40 and dropped


def test_a_frame_releases_the_nodes_it_kept_busy_though_the_links_moved() -> None:
    """Robots move between steps: a frame that started when node 2 heard its sender and
    ends after it no longer does still releases node 2 (a busy count kept for ever
    silenced whole teams), and node 2 then sends at once."""
    power = _all_in_range(3)
    medium = _medium(power)
    _at(medium, 0, 0.010)  # on the air until ~0.0119; 2 hears it: busy
    assert medium.sensed(2) == 1
    moved = power.copy()
    moved[0, 2] = moved[2, 0] = -200.0  # 2 moved out of range
    np.fill_diagonal(moved, np.nan)
    medium.set_power(moved)
    (_left,) = medium.advance(0.05)
    assert not any(medium.sensed(k) for k in range(3))
    medium.submit(2, 0.05, BITS, 2)
    (second,) = medium.advance(0.05) + medium.advance(0.2)
    assert second.start == pytest.approx(0.05)


def test_the_same_seeds_give_the_same_air() -> None:
    def run(seed: int) -> list[tuple[int, float, float]]:
        medium = _medium(_all_in_range(5), seed=seed)
        for sender in range(5):
            for _ in range(20):
                medium.submit(sender, 0.0, BITS, None)
        return [(f.sender, f.start, f.end) for f in medium.advance(1.0)]

    assert run(1) == run(1)
    assert run(1) != run(2)


def test_submitted_frames_arrive_spread_over_the_step() -> None:
    """A step publishes at one instant; its frames reach the MAC at instants of their own
    within it, so three robots' poses of one step do not all collide."""
    medium = _medium(_all_in_range(3))
    medium.advance(1.0)
    for sender in range(3):
        medium.submit(sender, 1.0, BITS, None)
    frames: list[Frame] = medium.advance(1.1)
    assert sorted({round(f.submitted, 9) for f in frames}) != [1.0]
    assert all(1.0 <= f.submitted < 1.1 for f in frames)
    assert not any(f.chunk_mw.any() for f in frames)
    assert math.isclose(min(f.submitted for f in frames), min(f.start for f in frames))


def test_a_node_without_a_radio_is_never_blocked() -> None:
    power = np.full((3, 3), -50.0)
    power[2, :] = power[:, 2] = np.nan  # the operator's virtual node
    medium = _medium(power)
    frames = _together(medium, [0, 2], 0.010)
    assert len(frames) == 2 and frames[0].start == frames[1].start
    ours, virtual = sorted(frames, key=lambda f: f.sender)
    assert not ours.blocked[2] and not virtual.blocked.any()
    assert not ours.chunk_mw.any()  # the virtual node's frame is no interference


# -- in a mission -------------------------------------------------------------------


def test_a_mission_on_the_shared_channel_counts_collisions_and_airtime(
    s1_resources: ScenarioResources,
) -> None:
    """S1 on the radio with the shared channel: the same result twice; every topic's
    collisions and airtime in the results; some poses and heartbeats collide; the
    per-sender queue of the same run has no collisions at all (its results have no such
    count)."""
    shared = _run_config(channel="shared")
    first = run_mission(shared, s1_resources)
    assert comparable(first) == comparable(run_mission(shared, s1_resources))
    messages = first.messages
    assert all("dropped_collision" in c and "airtime_s" in c for c in messages.values())
    assert messages["pose"]["dropped_collision"] > 0
    assert messages["heartbeat"]["dropped_collision"] > 0
    pose_airtime = messages["pose"]["airtime_s"]
    bits = (messages["pose"]["sent"] and pose_airtime / messages["pose"]["sent"]) * 1e6
    assert 1500 < bits < 3000  # a pose frame takes ~2 ms at 1 Mbit/s with its preamble
    queue = run_mission(_run_config(channel="queue"), s1_resources)
    assert all("dropped_collision" not in c for c in queue.messages.values())


def _run_config(channel: str) -> Any:
    from mrcomm.run.config import make_config
    from tests.golden.golden import SCENARIO

    return make_config(
        None, scenario=SCENARIO, network="radio", threshold="slt", behaviour="lf", seed=1,
        params={"network": {"channel": channel}},
    )  # fmt: skip


def test_live_mode_refuses_the_shared_channel(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    from tests.cli.test_signal_cli import mrcomm

    code, _, err = mrcomm(
        monkeypatch, capsys, "live", "s1", "--network", "radio", "--insecure",
        "--set", "network.channel=shared",
    )  # fmt: skip
    assert code == 2
    assert err.strip().count("\n") == 0 and "shared channel is simulation only" in err


@pytest.mark.parametrize("spl", [0, 40])
def test_frames_decided_together_or_one_by_one_give_the_same_mission(
    s1_resources: ScenarioResources, spl: int
) -> None:
    """The bus decides a step's frames on one topic together for many receivers
    (InProcessNetwork.batch_from) and one by one for few: the same errors, draws,
    decisions, counts and handler calls. S1 forced both ways, with and without SPL."""
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import Mission
    from tests.golden.golden import SCENARIO

    results = []
    for batch_from in (0, 10**6):
        config = make_config(
            None, scenario=SCENARIO, network="radio", threshold="slt", behaviour="lf",
            seed=2, spl=spl, params={"network": {"channel": "shared"}},
        )  # fmt: skip
        mission = Mission(config, s1_resources)
        mission.network.batch_from = batch_from
        results.append(comparable(mission.run()))
    assert results[0] == results[1]
    assert results[0]["messages"]["pose"]["dropped_collision"] > 0
