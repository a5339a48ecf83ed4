"""What a robot knows of its team mates, from the poses it received: each mate's last
pose, when it arrived (so its age can be asked), the role the mate announced and the
leader it follows. Collision avoidance and LF read mates from here.

A pose's age is counted from the time its sender stamped it (every member shares the
mission clock), so it includes the message's time in transit. :meth:`TeamView.known`
is the view a robot acts on: mates whose pose is too old left out, and the others moved
on along their last heading at their last speed for the pose's age (dead reckoning over
a short horizon: a robot at 0.26 m/s travels 5 cm per 0.2 s pose period, the size of
the localisation error, so a pose period or two of extrapolation corrects the lag of a
pose without inventing turns the mate may have made)."""

from __future__ import annotations

import math

from mrcomm.agents.collision import MateState
from mrcomm.messaging.messages import PoseMsg

#: The last pose message turned into a mate's state, and that state: a pose reaches
#: every mate in turn, so each builds the same immutable state once, not once per
#: receiver. One tuple, replaced whole, so runs in threads never see half an update.
_last_state: tuple[PoseMsg | None, MateState | None] = (None, None)


def mate_state(message: PoseMsg) -> MateState:
    """The state of the mate that sent ``message``, as collision avoidance reads it."""
    global _last_state
    last, state = _last_state
    if last is message and state is not None:
        return state
    state = MateState(
        message.sender,
        message.x,
        message.y,
        message.theta,
        message.v,
        message.goal_dist,
        message.stamp,
    )
    _last_state = (message, state)
    return state


class TeamView:
    """Each mate's last received pose, with the time it was received."""

    def __init__(self) -> None:
        self.poses: dict[str, MateState] = {}
        #: When each mate's last pose arrived (the receiver's clock).
        self.heard: dict[str, float] = {}
        #: When each mate's last pose was sent (its stamp, on the mission clock).
        self.stamps: dict[str, float] = {}
        self.roles: dict[str, str] = {}
        #: mate -> the robot it follows ("" when none).
        self.leaders: dict[str, str] = {}
        #: Mates whose process has gone, as the transport's liveliness says (live mode;
        #: always empty in simulation, where no process dies).
        self.departed: set[str] = set()

    def hear(self, message: PoseMsg, now: float) -> None:
        mate = message.sender
        self.poses[mate] = mate_state(message)
        self.heard[mate] = now
        self.stamps[mate] = message.stamp
        self.roles[mate] = message.role
        self.leaders[mate] = message.leader

    def age(self, mate: str, now: float) -> float:
        """Seconds since ``mate``'s last pose arrived (inf if never heard)."""
        heard = self.heard.get(mate)
        return math.inf if heard is None else now - heard

    def known(
        self, now: float, max_age: float | None, extrapolation: float
    ) -> dict[str, MateState]:
        """Each mate as a robot should act on it at ``now``: left out when its pose is
        older than ``max_age`` (None: never), moved on for its age (at most
        ``extrapolation`` s) along its heading at its speed."""
        if max_age is None and extrapolation <= 0:
            return self.poses  # the original robots' view: every last pose, as it came
        out: dict[str, MateState] = {}
        for mate, state in self.poses.items():
            age = max(0.0, now - self.stamps[mate])
            if max_age is not None and age > max_age:
                continue
            ahead = min(age, extrapolation) * state.v
            if ahead != 0.0:
                state = state._replace(
                    x=state.x + ahead * math.cos(state.theta),
                    y=state.y + ahead * math.sin(state.theta),
                )
            out[mate] = state
        return out

    def heard_within(self, seconds: float, now: float) -> bool:
        """Whether any mate's pose arrived less than ``seconds`` ago."""
        return any(now - t < seconds for t in self.heard.values())
