"""A large team's view of its mates kept as arrays (poses heard in the in-process bus's
step batches) answers which mates are near exactly as the loop over its mates does:
the same mates, in the order they were first heard, from the latest pose of each."""

from __future__ import annotations

import math
from collections.abc import Collection

import numpy as np
import pytest
from numpy.typing import NDArray

from mrcomm.agents.collision import Mate
from mrcomm.agents.team_view import (
    NEAR_ARRAYS_FROM,
    TeamView,
    near_numbers,
    near_numbers_numpy,
)
from mrcomm.messaging.messages import PoseMsg
from mrcomm.ports import Received, StepBatch

from .fakes import pose_of

MEMBERS = NEAR_ARRAYS_FROM + 50


def _steps(seed: int) -> list[list[tuple[int, PoseMsg]]]:
    """Twenty steps of poses of a team: each step a random subset of the members (the
    one receiver, member 0, never among them; some members first heard late) at random
    places in a 40 m square, so that near and far mates change from step to step."""
    rng = np.random.default_rng(seed)
    steps = []
    for _ in range(20):
        senders = rng.choice(
            np.arange(1, MEMBERS), size=int(rng.integers(1, MEMBERS)), replace=False
        )
        steps.append(
            [(int(s), pose_of(f"robot_{s}", *rng.uniform(0.0, 40.0, 2).tolist())) for s in senders]
        )
    return steps


def _received(step: list[tuple[int, PoseMsg]], ever: NDArray[np.bool_] | None = None) -> Received:
    """The step as the bus hands it over: a batch of everyone's poses (the receiver's
    own included, as a batch has it) and the receiver's share of it, in order. ``ever``:
    the bus's record of who has sent so far, updated with this batch (None: not kept)."""
    own = pose_of("robot_0", 20.0, 20.0)
    members = np.array([f"robot_{s}" for s in range(MEMBERS)], dtype=object)
    index = {name: number for number, name in enumerate(members.tolist())}
    senders = np.array([0, *(s for s, _ in step)], dtype=np.intp)
    if ever is not None:
        ever[senders] = True
    batch = StepBatch([own, *(m for _, m in step)], senders, members, index, ever)
    return Received(batch, np.arange(1, len(step) + 1))


def _in_box(mates: Collection[Mate], x: float, y: float, reach: float) -> list[Mate]:
    """The mates within ``reach`` along both axes, as the callers of near() test it."""
    return [m for m in mates if -reach <= m.x - x <= reach and -reach <= m.y - y <= reach]


def test_without_a_table_every_known_mate_is_a_candidate() -> None:
    view = TeamView()
    view.hear_all([pose_of("robot_1", 0.0, 0.0), pose_of("robot_2", 90.0, 0.0)], 0.0, "")
    assert [m.robot for m in view.near(0.0, 0.0, 1.0, 0.0, None, 0.0)] == ["robot_1", "robot_2"]


@pytest.mark.parametrize("kept", [False, True])
def test_the_arrays_find_the_near_mates_the_loop_finds(kept: bool) -> None:
    """Also when the bus keeps who has sent (a table that has heard them all then skips
    looking for new mates: the order they were first heard in stays the loop's)."""
    arrays, loop = TeamView(), TeamView()
    rng = np.random.default_rng(7)
    ever = np.zeros(MEMBERS, dtype=np.bool_) if kept else None
    checked = 0
    for now, step in enumerate(_steps(3)):
        arrays.hear_all(_received(step, ever), float(now), "robot_0")
        loop.hear_all([m for _, m in step], float(now), "robot_0")
        assert arrays._table is not None and loop._table is None
        assert list(arrays.poses.items()) == list(loop.poses.items())
        assert len(arrays.poses) == len(loop.poses) and "robot_0" not in arrays.poses
        assert arrays.poses.get("robot_0") is None and arrays.poses.get("nobody") is None
        assert list(arrays.heard.items()) == list(loop.heard.items())
        assert arrays.heard.get("robot_0") is None and arrays.age("robot_0", now) == math.inf
        for seconds in (0.5, 1.0, 2.5):
            assert arrays.heard_within(seconds, now + 1.0) == loop.heard_within(seconds, now + 1.0)
        for x, y in rng.uniform(-2.0, 42.0, (30, 2)).tolist():
            reach = float(rng.uniform(0.5, 6.0))
            near = arrays.near(x, y, reach, float(now), None, 0.0)
            assert near == _in_box(loop.near(x, y, reach, float(now), None, 0.0), x, y, reach)
            checked += len(near)
    assert checked > 100  # the queries found mates, not only empty answers


def test_a_mate_on_the_edge_of_reach_is_near_in_both() -> None:
    """The arrays' test is the loop's exactly (a mate exactly ``reach`` away counts)."""
    arrays, loop = TeamView(), TeamView()
    step = [(1, pose_of("robot_1", 10.0, 10.0)), (2, pose_of("robot_2", 12.5, 10.0))]
    arrays.hear_all(_received(step), 0.0, "robot_0")
    loop.hear_all([m for _, m in step], 0.0, "robot_0")
    for view in (arrays, loop):
        assert [
            m.robot for m in _in_box(view.near(10.0, 10.0, 2.5, 0.0, None, 0.0), 10.0, 10.0, 2.5)
        ] == [
            "robot_1",
            "robot_2",
        ]
    assert [m.robot for m in arrays.near(10.0, 10.0, 2.5, 0.0, None, 0.0)] == ["robot_1", "robot_2"]
    assert [m.robot for m in arrays.near(10.0, 10.0, 2.4, 0.0, None, 0.0)] == ["robot_1"]


def test_the_arrays_are_dropped_once_a_pose_arrives_otherwise() -> None:
    """Poses heard one at a time (or a batch with a mate twice) would leave the arrays
    behind: the view drops them for good and loops, with the same answers."""
    view = TeamView()
    steps = _steps(5)
    view.hear_all(_received(steps[0]), 0.0, "robot_0")
    assert view._table is not None
    heard = list(view.heard.items())
    poses = list(view.poses.items())
    view.hear(steps[1][0][1], 1.0)
    assert view._table is None and isinstance(view.poses, dict)
    late = steps[1][0][1]
    assert list(view.poses.items())[: len(poses)] == [
        (m, late if m == late.sender else p) for m, p in poses
    ]
    assert list(view.heard.items())[: len(heard)] == [
        (m, 1.0 if m == steps[1][0][1].sender else t) for m, t in heard
    ]
    view.hear_all(_received(steps[2]), 2.0, "robot_0")
    assert view._table is None
    twice = [(1, pose_of("robot_1", 1.0, 1.0)), (1, pose_of("robot_1", 2.0, 2.0))]
    fresh = TeamView()
    fresh.hear_all(_received(twice), 0.0, "robot_0")
    assert fresh._table is None and fresh.poses["robot_1"].x == 2.0


def test_a_receivers_share_reads_as_its_messages() -> None:
    step = [(4, pose_of("robot_4", 1.0, 0.0)), (9, pose_of("robot_9", 2.0, 0.0))]
    share = _received(step)
    assert len(share) == 2 and list(share) == [m for _, m in step]
    assert share[1] is step[1][1] and share[-1] is step[1][1] and share[:1] == [step[0][1]]


@pytest.mark.parametrize("members", [5, 120, 1000])
def test_the_compiled_query_finds_what_numpys_finds(members: int) -> None:
    """The one-pass query (compiled where numba is there) and numpy's expression give
    the same numbers in the same order: with mates never heard (NaN), mates exactly at
    the edge of reach, and so many found that the pass sorts instead of inserting."""
    rng = np.random.default_rng(members)
    xs, ys = rng.uniform(0.0, 30.0, (2, members))
    xs[rng.random(members) < 0.2] = np.nan  # never heard
    ys[:3] = ys[3]
    xs[:3] = xs[3] + np.array([-2.0, 2.0, 0.0])  # on the edge of a reach of 2
    first = rng.permutation(members).astype(np.int32)
    found_many = 0
    for x, y, reach in [(xs[3], ys[3], 2.0), *rng.uniform(0.0, 30.0, (40, 3)).tolist()]:
        if math.isnan(x):
            continue
        out = np.empty(members, dtype=np.intp)
        count = near_numbers(xs, ys, first, x, y, reach, out)
        expected = near_numbers_numpy(xs, ys, first, x, y, reach)
        assert out[:count].tolist() == expected.tolist()
        found_many = max(found_many, count)
    assert found_many > 16 or members < 20  # the sorting branch ran
