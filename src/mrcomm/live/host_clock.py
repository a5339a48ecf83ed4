"""Host-clock stepping of a live agent (``mrcomm agent --clock host``; issue 7 §3).

On a real robot there is no world clock: the agent steps every ``dt`` on its own
host's monotonic clock while its base (the robot's navigation stack; here the world's
simulated body) reports its state asynchronously. This module provides:

* :class:`HostClock` — mission time on this host's monotonic clock. It starts from an
  agreed mission start (``t0 = monotonic() - start_time``) and schedules step ``k`` at
  ``t0 + k * dt``: the schedule never drifts, and a step that comes late by more than
  one ``dt`` is skipped (counted) rather than run in a burst.
* :class:`HostClockAgent` — the agent process (:class:`~mrcomm.live.agent.AgentProcess`)
  stepped on a :class:`HostClock`. The world's ticks only update the base state and end
  the mission; the first tick is the agreed start (on a real robot: the assignment or
  a start message, see docs/PHYSICAL.md). Every journal line carries the agent's own
  time. Its ``clock`` lines pair that time with the host's wall clock at which this
  clock read it (as a shared-clock agent pairs a tick's time with its arrival), so the
  offsets collection derives keep their meaning; they also say how stale the base
  state is (``base_age``: own time minus the latest tick's) and how many steps were
  skipped. The agent ends by itself at ``--max-time`` on its own clock if no end of
  mission has reached it by then.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from mrcomm.errors import InputError
from mrcomm.live.agent import HEARTBEAT_PERIOD, SNAPSHOT_PERIOD, AgentProcess
from mrcomm.live.settings import LiveSettings
from mrcomm.net.zenoh_node import Incoming, drain

_EPS = 1e-6  # of a step: a time read as 2.9999999 steps is step 3


class HostClock:
    """Mission time on a monotonic clock, stepped every ``dt`` from an agreed start."""

    def __init__(
        self,
        dt: float,
        monotonic: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.dt = dt
        self._monotonic = monotonic
        self._wall = wall
        self._t0: float | None = None
        self._last: int | None = None  # the last step taken
        #: Steps skipped because the process ran more than a step late.
        self.skipped = 0
        #: Worst delay (s) between a step's time and when it ran.
        self.max_late = 0.0

    @property
    def started(self) -> bool:
        return self._t0 is not None

    def start(self, mission_time: float) -> None:
        """The mission is at ``mission_time`` now: the next step is the current one."""
        self._t0 = self._monotonic() - mission_time
        self._last = None

    def time(self) -> float:
        """The mission time now on this clock (exact, between steps too)."""
        assert self._t0 is not None, "clock not started"
        return self._monotonic() - self._t0

    def _current(self) -> int:
        return math.floor(self.time() / self.dt + _EPS)

    def due(self) -> bool:
        """A step is due (not taken yet)."""
        return self.started and (self._last is None or self._current() > self._last)

    def until_next(self) -> float:
        """Seconds until the next step is due (0 if it is); inf before the start."""
        if self._t0 is None:
            return math.inf
        if self._last is None:
            return 0.0
        return max(self._t0 + (self._last + 1) * self.dt - self._monotonic(), 0.0)

    def take(self) -> float | None:
        """The time of the step to run now, or None if none is due. Only the latest
        due step runs: those it overtook are skipped, never run in a burst."""
        if not self.due():
            return None
        k = self._current()
        if self._last is not None:
            self.skipped += k - self._last - 1
        self._last = k
        self.max_late = max(self.max_late, self.time() - k * self.dt)
        return round(k * self.dt, 9)

    def wall_of(self, mission_time: float) -> float:
        """The host's wall clock (s since the epoch) when this clock read ``mission_time``."""
        return self._wall() - (self.time() - mission_time)


def check_world_speed(speed: float) -> None:
    """A host clock runs in real seconds: a world running faster or slower than real
    time would leave the robot's body and its agent in different times."""
    if speed != 1.0:
        raise InputError(
            f"the world runs at --speed {speed:g}: an agent on its host's clock needs "
            "a world at --speed 1",
            field="--clock",
        )


class HostClockAgent(AgentProcess):
    """An agent process stepped every ``dt`` on its host's monotonic clock."""

    def __init__(
        self,
        settings: LiveSettings,
        agent: str,
        incarnation: int,
        clock: HostClock | None = None,
    ) -> None:
        super().__init__(settings, agent, incarnation)
        self.clock = clock if clock is not None else HostClock(settings.run.dt)
        self.max_base_age = 0.0

    def _loop(self) -> None:
        while not self.ended:
            self._heartbeat()
            wait = min(HEARTBEAT_PERIOD / 2, self.clock.until_next())
            # A flood of messages must not hold the step back: a due step ends the drain.
            drain(self.node.poll, lambda item: self._handle(item) or self.clock.due(), wait)
            if self.ended:
                return
            now = self.clock.take()
            if now is not None:
                self._host_step(now)
            self.journal.flush()

    def _on_tick(self, item: Incoming) -> None:
        """A tick only brings the base state (and the end); the first one starts the
        clock at the tick's time: the mission start the team agreed on."""
        tick = self._take_tick(item)
        if tick is None:
            return
        if tick.end:
            self._end(tick.end_time, tick.timed_out)
            return
        if not self.clock.started:
            check_world_speed(tick.speed)
            self.clock.start(tick.time)
            self._first_tick(tick.time)

    def _host_step(self, now: float) -> None:
        self.now = now
        self.bus.release(now)
        limit = self.settings.run.max_time
        if now >= limit - 1e-9:
            # No end of mission reached us (a world gone, or none: a real robot).
            self.journal.write("own_time_limit", time=now)
            self._end(limit, True)
            return
        self._step(now)
        age = now - self.tick_time
        self.max_base_age = max(self.max_base_age, age)
        if now >= self._next_snapshot - 1e-9:
            # On the grid of the period, so the times match the world's clock lines.
            self._next_snapshot = (math.floor(now / SNAPSHOT_PERIOD + _EPS) + 1) * SNAPSHOT_PERIOD
            self._snapshot(
                wall=self.clock.wall_of(now),
                clock="host",
                base_age=round(age, 6),
                max_base_age=round(self.max_base_age, 6),
                skipped=self.clock.skipped,
                late=round(self.clock.max_late, 6),
            )
