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
from collections.abc import Mapping, Sequence

from mrcomm.agents.collision import Mate, MateState
from mrcomm.messaging.messages import PoseMsg


class TeamView:
    """Each mate's last received pose, with the time it was received.

    The pose message itself is kept: it carries everything a robot reads of a mate
    (position, heading, speed, goal distance, stamp, role, leader), and in a large team
    storing one reference per received pose, rather than a state built from it, is
    what keeps hearing a pose cheap (most of a large team's work)."""

    def __init__(self) -> None:
        #: Each mate's last pose message (a :class:`Mate` as collision avoidance reads it).
        self.poses: dict[str, PoseMsg] = {}
        #: When each mate's last pose arrived (the receiver's clock).
        self.heard: dict[str, float] = {}
        #: Mates whose process has gone, as the transport's liveliness says (live mode;
        #: always empty in simulation, where no process dies).
        self.departed: set[str] = set()

    def hear(self, message: PoseMsg, now: float) -> None:
        """A mate's pose arrived at ``now``."""
        self.hear_all((message,), now, "")

    def hear_all(self, messages: Sequence[PoseMsg], now: float, own: str) -> None:
        """Poses that arrived together, in order (the robot's own, ``own``, left out):
        the same as hearing each in turn (the last of a mate's wins; mates keep the order
        they were first heard in), in two dict updates."""
        latest = {message.sender: message for message in messages}
        latest.pop(own, None)
        self.poses.update(latest)
        self.heard.update(dict.fromkeys(latest, now))

    def role(self, mate: str) -> str | None:
        """The role ``mate`` announced in its last pose (None if never heard)."""
        message = self.poses.get(mate)
        return None if message is None else message.role

    def leader(self, mate: str) -> str | None:
        """The robot ``mate`` said it follows ("" when none; None if never heard)."""
        message = self.poses.get(mate)
        return None if message is None else message.leader

    def age(self, mate: str, now: float) -> float:
        """Seconds since ``mate``'s last pose arrived (inf if never heard)."""
        heard = self.heard.get(mate)
        return math.inf if heard is None else now - heard

    def known(self, now: float, max_age: float | None, extrapolation: float) -> Mapping[str, Mate]:
        """Each mate as a robot should act on it at ``now``: left out when its pose is
        older than ``max_age`` (None: never), moved on for its age (at most
        ``extrapolation`` s) along its heading at its speed."""
        if max_age is None and extrapolation <= 0:
            return self.poses  # the original robots' view: every last pose, as it came
        out: dict[str, Mate] = {}
        for mate, pose in self.poses.items():
            age = max(0.0, now - pose.stamp)
            if max_age is not None and age > max_age:
                continue
            ahead = min(age, extrapolation) * pose.v
            if ahead == 0.0:
                out[mate] = pose
                continue
            out[mate] = MateState(
                pose.sender,
                pose.x + ahead * math.cos(pose.theta),
                pose.y + ahead * math.sin(pose.theta),
                pose.theta,
                pose.v,
                pose.goal_dist,
                pose.stamp,
            )
        return out

    def heard_within(self, seconds: float, now: float) -> bool:
        """Whether any mate's pose arrived less than ``seconds`` ago."""
        return any(now - t < seconds for t in self.heard.values())
