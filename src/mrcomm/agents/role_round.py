"""LF's role-assignment round, as one part of the executor: what a robot collected in
the round it is in — the round number, every member's utility and role as heard, who
named this robot leader and when. The executor does the talking (utility and role
messages at 4 Hz), decides with :func:`mrcomm.agents.lf_groups.round_leaders` (of which
:meth:`RoleRound.best` is the one-group case) and makes the state changes."""

from __future__ import annotations

from collections.abc import Callable

from mrcomm.metrics import labels as L


class RoleRound:
    """The round one robot is in."""

    def __init__(self, robot: str) -> None:
        self.robot = robot
        self.number = 0
        self.scores: dict[str, float] = {}
        self.roles: dict[str, str] = {}
        #: Members that named this robot leader in this round, and when.
        self.confirmed_at: dict[str, float] = {}
        self.decided_at = 0.0
        self.next_announce = 0.0
        #: The newest round heard of and not joined (LF in groups: another group's).
        self.passed = 0

    def open(self, number: int, utility: float, now: float) -> None:
        """Start collecting round ``number`` with this robot's own utility."""
        self.number = number
        self.scores = {self.robot: utility}
        self.roles = {}
        self.confirmed_at = {}
        self.next_announce = now

    def pass_by(self, number: int) -> None:
        """Round ``number`` was heard of and not joined."""
        self.passed = max(self.passed, number)

    def next_number(self) -> int:
        """The number of a round this robot opens: newer than any it has heard of, joined
        or not. A robot that reused the number of a round others had settled while it
        was busy joined that round late, through its members' answers, and groups grew
        past ``group_size`` (eight robots behind one leader in S2)."""
        return max(self.number, self.passed) + 1

    def hear_utility(self, member: str, utility: float) -> None:
        self.scores.setdefault(member, utility)

    def hear_role(self, member: str, role: str, leader: str, now: float) -> None:
        self.roles[member] = role
        if leader == self.robot:
            self.confirmed_at[member] = now
        self.scores.setdefault(member, 0.0)  # it is a member of the round

    def has_every_score(self, members: tuple[str, ...]) -> bool:
        return len(self.scores) == len(members)

    def has_every_role(self) -> bool:
        return all(m in self.roles for m in self.scores)

    @property
    def alone(self) -> bool:
        """Nobody else's utility was heard."""
        return len(self.scores) == 1

    def best(self, rank: Callable[[str], float]) -> tuple[str, float]:
        """The member with the highest utility (ties: the lower rank) and its utility."""
        best = max(self.scores, key=lambda r: (self.scores[r], -rank(r)))
        return best, self.scores[best]

    def settle(self, leader: str, now: float) -> None:
        """The round is decided: ``leader`` leads; announce this robot's role now."""
        self.decided_at = now
        self.roles[self.robot] = L.ROLE_LEADER if leader == self.robot else L.ROLE_FOLLOWER
        self.next_announce = now
