"""When an LF leader holds for its followers: the judgement of each follower it waits
for, at the pose rate.

A follower holds its leader while its link is in warning (``hold_distance`` unset: the
threshold in use), or while it is further than ``hold_distance`` (the original's
Algorithm 5 read literally: beyond the communication limit). A follower is judged where
its last pose put it, or with ``hold_prediction`` where it should be by now
(:func:`mrcomm.agents.lf_route.predicted_follower`); with ``chain_hops`` > 1 its link
may go through mates. ``hold_grace`` lets a follower stay in warning that long before the
leader holds. ``hold_judges`` "furthest" judges only the follower furthest from the
leader (the original's "too far from the furthest follower robot(s)", thesis line 1631),
where the default judges each. With a measured signal (ESD) a follower within
``refollow_distance`` never holds its leader: the two directions of a measured link
differ, and a follower that measures no warning waits there while the leader's reading
of it may warn (shadowing, a wall, the weaker direction): the two would wait for each
other for ever. A signal judged from positions (SLT, SSD) is the same both ways: such a
follower sees the warning too and comes closer.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from mrcomm.agents.lf_route import predicted_follower
from mrcomm.world.geometry import Pose

if TYPE_CHECKING:
    from mrcomm.agents.lf import LeaderFollowerExecutor


class LeaderHold:
    """A leader's judgement of its followers, with what it remembers between steps."""

    def __init__(self) -> None:
        self._next_check = 0.0
        self._were_out = False
        self._out_since: float | None = None  # since when a follower has been in warning

    def followers_out(self, leader: LeaderFollowerExecutor) -> bool:
        """Whether a follower holds ``leader`` now (judged again once per pose period:
        followers' poses arrive at that rate)."""
        now = leader._now
        if now < self._next_check:
            return self._were_out
        self._next_check = now + leader.params.pose_period
        out = self._judge(leader)
        if not out:
            self._out_since = None
        elif self._out_since is None:
            self._out_since = now
        # hold_grace: a follower may stay in warning this long before the leader holds,
        # so the group uses its connection area up to the communication limit.
        grace = leader.lf.hold_grace
        self._were_out = out and (grace <= 0 or now - (self._out_since or now) >= grace)
        return self._were_out

    def _judge(self, leader: LeaderFollowerExecutor) -> bool:
        pose = leader.base.pose
        lf = leader.lf
        furthest: tuple[float, str, float, float] | None = None  # hold_judges "furthest"
        for mate in leader.team:
            known = leader.mates.get(mate)
            if known is None or leader.team_view.age(mate, leader._now) > lf.lost_timeout:
                continue
            if not leader._follows_me(mate):
                continue
            age = max(0.0, leader._now - known.stamp)
            x, y = predicted_follower(known, pose, age, lf.hold_prediction, lf.follow_distance)
            if lf.hold_judges == "furthest":
                distance = math.hypot(x - pose.x, y - pose.y)
                if furthest is None or distance > furthest[0]:
                    furthest = (distance, mate, x, y)
                continue
            if self._too_far(leader, mate, pose, x, y):
                return True
        if furthest is not None:
            _, mate, x, y = furthest
            return self._too_far(leader, mate, pose, x, y)
        return False

    @staticmethod
    def _too_far(leader: LeaderFollowerExecutor, mate: str, pose: Pose, x: float, y: float) -> bool:
        """Whether a follower at (x, y) holds the leader (see the module docstring)."""
        lf = leader.lf
        distance = math.hypot(x - pose.x, y - pose.y)
        if lf.hold_distance is not None:
            return distance > lf.hold_distance
        if distance <= lf.refollow_distance and not leader.link_sensor.positional:
            return False
        return leader._link_warns(mate, pose, x, y)
