"""What a robot knows of its team mates, from the poses it received: each mate's last
pose, when it arrived (so its age can be asked), the role the mate announced and the
leader it follows. Collision avoidance and LF read mates from here."""

from __future__ import annotations

import math

from mrcomm.agents.collision import MateState
from mrcomm.messaging.messages import PoseMsg


class TeamView:
    """Each mate's last received pose, with the time it was received."""

    def __init__(self) -> None:
        self.poses: dict[str, MateState] = {}
        #: When each mate's last pose arrived (the receiver's clock).
        self.heard: dict[str, float] = {}
        self.roles: dict[str, str] = {}
        #: mate -> the robot it follows ("" when none).
        self.leaders: dict[str, str] = {}
        #: Mates whose process has gone, as the transport's liveliness says (live mode;
        #: always empty in simulation, where no process dies).
        self.departed: set[str] = set()

    def hear(self, message: PoseMsg, now: float) -> None:
        mate = message.sender
        self.poses[mate] = MateState(
            mate, message.x, message.y, message.theta, message.v, message.goal_dist
        )
        self.heard[mate] = now
        self.roles[mate] = message.role
        self.leaders[mate] = message.leader

    def age(self, mate: str, now: float) -> float:
        """Seconds since ``mate``'s last pose arrived (inf if never heard)."""
        heard = self.heard.get(mate)
        return math.inf if heard is None else now - heard

    def heard_within(self, seconds: float, now: float) -> bool:
        """Whether any mate's pose arrived less than ``seconds`` ago."""
        return any(now - t < seconds for t in self.heard.values())
