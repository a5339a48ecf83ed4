"""The tick guard: a tick the world cannot have sent is refused — far in the future,
not finite, negative, or at another speed — while the world's own ticks, late or early
by up to the slack, pass."""

from __future__ import annotations

import math

from mrcomm.live.protocol import Tick
from mrcomm.live.tick_guard import TickGuard, tick_limit


def tick(time: float, speed: float = 20.0, **kw: object) -> Tick:
    return Tick(time=time, speed=speed, states=(), **kw)  # type: ignore[arg-type]


def test_the_worlds_ticks_pass_and_a_tick_from_the_future_does_not() -> None:
    guard = TickGuard(slack_wall=2.0)
    assert guard.plausible(tick(10.0), wall=100.0)  # the anchor
    # 1 wall s later the world is at most 20 s of mission time further (+ 2 s slack).
    assert guard.plausible(tick(30.0), wall=101.0)
    assert guard.plausible(tick(69.9), wall=101.0)  # 10 + 20 x (1 + 2)
    assert not guard.plausible(tick(70.1), wall=101.0)
    assert not guard.plausible(tick(1e9), wall=101.0)  # the tick that froze every agent
    assert guard.plausible(tick(5.0), wall=101.0)  # stale ones are the caller's business
    # An end tick may not end the mission beyond the reachable time either.
    assert not guard.plausible(tick(30.0, end=True, end_time=1e6), wall=101.0)
    assert guard.plausible(tick(30.0, end=True, end_time=29.0), wall=101.0)


def test_malformed_ticks_are_refused_even_first() -> None:
    for bad in (tick(math.nan), tick(math.inf), tick(-1.0), tick(1.0, speed=0.0),
                tick(1.0, speed=math.inf), tick(1.0, end=True, end_time=math.nan)):  # fmt: skip
        assert not TickGuard().plausible(bad, wall=0.0), bad
    guard = TickGuard()
    assert guard.plausible(tick(0.0, speed=10.0), wall=0.0)
    assert not guard.plausible(tick(0.1, speed=1e9), wall=0.01)  # a world keeps its speed


def test_ticks_beyond_the_mission_limit_or_at_another_speed_are_refused_even_first() -> None:
    """Known limits need no anchor: a forged first tick far in the future, or at another
    speed than the world's, would otherwise become the anchor and make every genuine
    tick look stale or wrong."""
    limit = tick_limit(max_time=600.0, dt=0.1)
    guard = TickGuard(limit=limit, speed=20.0)
    assert not guard.plausible(tick(1e9), wall=0.0)
    assert not guard.plausible(tick(600.2), wall=0.0)
    assert not guard.plausible(tick(1.0, speed=1e9), wall=0.0)
    assert not guard.plausible(tick(1.0, end=True, end_time=1e6), wall=0.0)
    assert guard.plausible(tick(0.0), wall=0.0)  # the world's first tick: the anchor
    # The world's last ticks: the step reaching the limit, and its end announcement.
    assert guard.plausible(tick(600.0 + 0.1), wall=40.0)
    assert guard.plausible(tick(600.1, end=True, end_time=600.1, timed_out=True), wall=40.0)
    assert not guard.plausible(tick(600.0 + 0.2), wall=40.0)
