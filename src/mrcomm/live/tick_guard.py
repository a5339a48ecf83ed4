"""Clock ticks a world cannot have sent are refused (defence in depth without TLS).

Without authentication (``--insecure``) anyone on the network can publish on the
world's tick key. The one forged tick that did harm was a tick far in the future:
every later genuine tick looked stale, and the agents froze. A receiver can judge a
tick's plausibility from what it has already seen, without trusting the sender: the
world publishes tick ``k`` (time ``k·dt``) no earlier than ``k·dt / speed`` wall
seconds after its first, so after a tick (``t0`` received at wall ``w0``) no genuine
tick can carry a time beyond ``t0 + speed·(w − w0)`` plus the first tick's delivery
delay. :class:`TickGuard` anchors on the first tick it accepts and refuses a tick:

* whose time or end time is not finite or negative;
* whose time or end time is beyond the mission's time limit (the world ends the
  mission there: no genuine tick is later than the limit plus one step);
* whose ``speed`` differs from the expected one (the world's ``--speed``, when the
  receiver knows it: an agent on its host's clock needs 1) or from the anchor's (a
  world's speed never changes);
* whose time runs ahead of that bound by more than ``slack_wall`` wall seconds.

It cannot tell a forged tick that is plausible (an ``end`` tick with a believable time,
say) from the world's, nor a forged first tick within the limits (it becomes the anchor;
such a tick's time can hold a receiver back at most until the world's clock reaches it,
as the limit bounds it): only the team's certificates and ACL stop those (docs/LIVE.md).
"""

from __future__ import annotations

import math

from mrcomm.live.protocol import Tick

#: The cause a refused tick is counted under (with the bus edge's causes).
IMPLAUSIBLE_TICK = "implausible_tick"
#: Wall seconds of delivery delay (and scheduling jitter) a genuine tick may make up.
SLACK_WALL = 2.0


class TickGuard:
    """Judges each received tick against the first one accepted (see module doc).

    ``speed``: the world's pace if known (None: whatever the first tick says);
    ``limit``: the latest mission time a genuine tick can carry (None: no limit)."""

    def __init__(
        self,
        slack_wall: float = SLACK_WALL,
        *,
        speed: float | None = None,
        limit: float | None = None,
    ) -> None:
        self.slack_wall = slack_wall
        self.speed = speed
        self.limit = limit
        self._anchor: tuple[float, float, float] | None = None  # (time, wall, speed)

    def plausible(self, tick: Tick, wall: float) -> bool:
        """Whether ``tick``, received at monotonic wall time ``wall``, may be the world's."""
        if not (math.isfinite(tick.time) and math.isfinite(tick.end_time)):
            return False
        if tick.time < 0 or tick.end_time < 0 or not (math.isfinite(tick.speed) and tick.speed > 0):
            return False
        if self.limit is not None and max(tick.time, tick.end_time) > self.limit:
            return False
        if self.speed is not None and tick.speed != self.speed:
            return False
        if self._anchor is None:
            self._anchor = (tick.time, wall, tick.speed)
            return True
        time0, wall0, speed = self._anchor
        if tick.speed != speed:
            return False
        reachable = time0 + speed * (wall - wall0 + self.slack_wall)
        return tick.time <= reachable and (not tick.end or tick.end_time <= reachable)


def tick_limit(max_time: float, dt: float) -> float:
    """The latest time a genuine tick of a mission limited to ``max_time`` can carry:
    the world stops at the first step at or beyond the limit (and announces the end
    with that step's time)."""
    return max_time + dt + 1e-6
