"""A robot's team mates: the team its assignment named, without the robot itself.

Every robot of a run receives the same team in its assignment. Copying it without the
robot's own name would hold one tuple of N - 1 names per robot: N² references, 0.8 GB at
10,000 robots. :class:`Mates` reads the one shared tuple instead and skips the robot's own
place in it, so it costs the same whatever the team's size, and iterates, counts, indexes
and compares like the tuple it replaces (the same names in the same order).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from itertools import chain, islice
from typing import overload


class Mates(Sequence[str]):
    """``team`` without ``robot``, in ``team``'s order, read from ``team`` itself."""

    __slots__ = ("_robot", "_skip", "_team")

    def __init__(self, team: tuple[str, ...], robot: str) -> None:
        self._team = team
        self._robot = robot
        # The robot's place in the team (len(team) when it is not a member: nothing to
        # skip).
        try:
            self._skip = team.index(robot)
        except ValueError:
            self._skip = len(team)
            return
        try:  # An assigner names each robot once; a team from a peer may not.
            team.index(robot, self._skip + 1)
        except ValueError:
            return
        self._team = tuple(name for name in team if name != robot)
        self._skip = len(self._team)

    def __len__(self) -> int:
        return len(self._team) - (self._skip < len(self._team))

    @overload
    def __getitem__(self, index: int) -> str: ...
    @overload
    def __getitem__(self, index: slice) -> tuple[str, ...]: ...
    def __getitem__(self, index: int | slice) -> str | tuple[str, ...]:
        if isinstance(index, slice):
            return tuple(self)[index]
        size = len(self)
        if not -size <= index < size:
            raise IndexError("mate index out of range")
        index %= size
        return self._team[index + (index >= self._skip)]

    def __iter__(self) -> Iterator[str]:
        team, skip = self._team, self._skip
        return chain(islice(team, skip), islice(team, skip + 1, None))

    def __contains__(self, name: object) -> bool:
        return name != self._robot and name in self._team

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Sequence) and not isinstance(other, str):
            return tuple(self) == tuple(other)
        return NotImplemented

    def __hash__(self) -> int:
        return hash(tuple(self))

    def __repr__(self) -> str:
        return f"Mates({tuple(self)!r})"
