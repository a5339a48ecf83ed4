"""SilentMembers finds exactly the members a full look through the team finds."""

from __future__ import annotations

import random

from mrcomm.messaging.aon_lease import SilentMembers


def _full_look(heard: dict[str, float], bits: dict[str, int], now: float, lease: float) -> int:
    """What the endpoint computed before: every member's last time, compared."""
    expired = 0
    for member, time in heard.items():
        if now - time > lease:
            expired |= bits[member]
    return expired


def test_the_same_members_as_a_full_look_at_every_step() -> None:
    for seed in range(20):
        rng = random.Random(seed)
        members = [f"robot_{i}" for i in range(rng.randint(1, 30))]
        bits = {m: 1 << i for i, m in enumerate(members)}
        lease = rng.choice([0.3, 1.0, 2.5])
        silence = SilentMembers(lease, bits)
        heard: dict[str, float] = {}
        # Some members are heard at the first step, the others only later or never.
        for m in members:
            if rng.random() < 0.7:
                silence.heard_first(m, 0.0)
                heard.setdefault(m, 0.0)
        now = 0.0
        for _ in range(400):
            now = round(now + 0.1, 9)
            for m in members:
                # Bursts of silence longer than the lease, and members heard often.
                if rng.random() < (0.02 if int(now) % 7 < 4 else 0.6):
                    silence.heard(m, now)
                    heard[m] = now
            assert silence.update(now) == _full_look(heard, bits, now, lease), (seed, now)


def test_a_member_heard_again_is_no_longer_silent_at_the_next_update() -> None:
    bits = {"a": 1, "b": 2}
    silence = SilentMembers(1.0, bits)
    silence.heard_first("a", 0.0)
    silence.heard_first("b", 0.0)
    assert silence.update(0.5) == 0
    silence.heard("b", 0.9)
    assert silence.update(1.5) == 1  # a: 1.5 s; b: 0.6 s
    assert silence.update(2.0) == 3
    silence.heard("a", 2.0)
    assert silence.bitmap == 3  # as of the last update, until the next one
    assert silence.update(2.1) == 2
    silence.heard_first("a", 0.0)  # already heard: changes nothing
    assert silence.update(2.2) == 2
    assert silence.last_heard("a") == 2.0


def test_a_time_given_earlier_than_before_is_still_taken_as_the_last() -> None:
    silence = SilentMembers(1.0, {"a": 1})
    silence.heard("a", 5.0)
    silence.heard("a", 3.0)
    assert silence.update(4.5) == 1


def test_heard_at_least_keeps_the_later_time() -> None:
    silence = SilentMembers(1.0, {"a": 1})
    silence.heard_at_least("a", 2.0)
    silence.heard_at_least("a", 1.0)
    assert silence.last_heard("a") == 2.0
    assert silence.update(3.5) == 1
    silence.heard_at_least("a", 1.0)  # older than its last: still silent
    assert silence.update(3.6) == 1
    silence.heard_at_least("a", 3.6)
    assert silence.update(3.7) == 0


def test_the_paused_messages_are_those_is_paused_names_at_every_tick() -> None:
    """An endpoint's split of its messages into paused and active, kept up to date where
    bits, reports and silent members change, is the one asking every message gives —
    through lossy exchanges, members cut off past the lease and coming back."""
    from mrcomm.messaging.aon_lease import is_paused
    from tests.messaging.aon_team import AonTeam
    from tests.messaging.fakenet import Cut, FakeNet

    def check(team: AonTeam) -> None:
        for endpoint in team.endpoints.values():
            states = endpoint._states
            full, expired = endpoint._team.full, endpoint._expired_bits
            paused = {m for m, st in states.items() if is_paused(st, full, expired)}
            assert endpoint._pauses.paused == paused
            assert set(endpoint._pauses.active) == set(states) - paused
            assert all(endpoint._pauses.active[m] is states[m] for m in endpoint._pauses.active)

    seen_paused = 0
    for seed in range(6):
        members = [f"r{i}" for i in range(5)]
        cuts = [Cut("r3", None, 2.0, 40.0 + 10 * seed), Cut("r4", None, 0.0, 25.0)]
        net = FakeNet(members, seed=seed, loss=0.3, cuts=cuts)
        team = AonTeam(net, lease=5.0, beacons=True)
        net.tick()
        for k, sender in enumerate(["r0", "r1", "r2", "r0", "r1"]):
            team.send(sender)
            for _ in range(10 + 7 * k):
                net.tick()
                check(team)
        while net.now < 120.0 and not team.all_done():
            net.tick()
            check(team)
            seen_paused += sum(len(e._pauses.paused) for e in team.endpoints.values())
        assert team.all_done() and not team.violations
    assert seen_paused > 0  # the exchanges did pause messages
