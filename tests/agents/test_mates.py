"""A robot's mates read from the shared team equal the tuple they replace."""

from __future__ import annotations

import pytest

from mrcomm.agents.mates import Mates


def _copied(team: tuple[str, ...], robot: str) -> tuple[str, ...]:
    return tuple(name for name in team if name != robot)


@pytest.mark.parametrize(
    ("team", "robot"),
    [
        (("a", "b", "c"), "a"),
        (("a", "b", "c"), "b"),
        (("a", "b", "c"), "c"),
        (("a", "b", "c"), "x"),  # not a member
        (("a",), "a"),
        ((), "a"),
        (("a", "b", "a", "c"), "a"),  # a peer's team naming the robot twice
    ],
)
def test_mates_behave_as_the_copied_tuple(team: tuple[str, ...], robot: str) -> None:
    mates, copy = Mates(team, robot), _copied(team, robot)
    assert tuple(mates) == copy
    assert list(iter(mates)) == list(copy)
    assert len(mates) == len(copy)
    assert bool(mates) == bool(copy)
    assert mates == copy and copy == mates
    assert hash(mates) == hash(copy)
    assert (*mates, robot) == (*copy, robot)
    for k in range(-len(copy), len(copy)):
        assert mates[k] == copy[k]
    for k in (len(copy), -len(copy) - 1):
        with pytest.raises(IndexError):
            mates[k]
    assert mates[1:] == copy[1:]
    for name in {*team, robot, "nobody"}:
        assert (name in mates) == (name in copy)
    assert mates.index(copy[-1]) == copy.index(copy[-1]) if copy else True


def test_mates_share_the_team_instead_of_copying_it() -> None:
    team = tuple(f"robot_{k}" for k in range(1000))
    views = [Mates(team, name) for name in team]
    assert all(view._team is team for view in views)
