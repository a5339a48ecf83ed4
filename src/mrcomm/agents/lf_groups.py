"""LF in groups: which members of a role round lead and whom each of the others follows,
so a large team splits into groups of about ``group_size`` instead of one leader
dragging everyone.

A round of ``n`` members elects ``k = ceil(n / group_size)`` leaders: the ``k`` highest
utilities (ties by the team-wide random order), among members that have work (utility
above 0). Every other member follows the leader nearest to it (straight-line distance
from where it last heard of each; ties by the random order). With ``n <= group_size``
this is the original rule: one leader, the highest utility, followed by everyone.

Each member decides with the utilities it collected, so under loss two members may
count different leaders; a member that follows a robot whose own poses then say it
does not lead leaves the roles (LF's "leader no longer leads"), and the next round
sorts it out. A leader waits only for the mates whose poses say they follow it, so a
group holds for its own members and never for another group's, and a group at work is
not pulled into another group's round (:func:`joins`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping


def round_leaders(
    scores: Mapping[str, float], rank: Callable[[str], float], group_size: int
) -> list[str]:
    """The leaders of a round with these utilities, best first (empty: nobody has work)."""
    k = max(1, math.ceil(len(scores) / group_size))
    order = sorted(scores, key=lambda robot: (-scores[robot], rank(robot)))
    return [robot for robot in order[:k] if scores[robot] > 0.0]


def nearest_leader(
    leaders: list[str],
    positions: Mapping[str, tuple[float, float]],
    own: tuple[float, float],
    rank: Callable[[str], float],
) -> str:
    """The leader to follow: the nearest by its last known position (unknown: last),
    ties by the random order."""

    def distance(leader: str) -> float:
        where = positions.get(leader)
        return math.inf if where is None else math.hypot(where[0] - own[0], where[1] - own[1])

    return min(leaders, key=lambda leader: (distance(leader), rank(leader)))


def joins(
    top: str,
    sender: str,
    leader: str | None,
    senders_leader: str | None,
    follows_me: Callable[[], bool],
    idle: bool = False,
) -> bool:
    """Whether a member in top state ``top`` joins a newer round ``sender`` opened or is
    in. A group at work is not pulled apart by another group's round: a leader joins only
    a round of a robot that follows it, a follower only one of its leader or of a robot
    that follows the same leader; a robot in no group (NA, assigning, regrouping,
    reporting) joins any. In a team of 100 every link warning of a robot without a role
    opened a round that spread to everyone in earshot: the team spent three quarters of
    its time assigning roles. An ``idle`` robot (its work done and reported) joins none:
    it would follow, and at the end of a mission every idle robot in earshot followed the
    one robot with work left (a leader with seven followers crawled to the time limit);
    it stays where it is, making way."""
    if idle:
        return False
    if top == "leader":
        return follows_me()
    if top == "follower":
        return sender == leader or (leader is not None and senders_leader == leader)
    return True
