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
