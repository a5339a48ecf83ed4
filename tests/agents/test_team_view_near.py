"""A large team's view of its mates read from the bus's store of latest poses
(:class:`~mrcomm.messaging.latest.LatestMessages`, written for every receiver of a step
at once) answers as the view that hears each pose itself does: the same mates, in the
order they were first heard, from the latest pose of each."""

from __future__ import annotations

import math
from collections.abc import Collection

import numpy as np
import pytest

from mrcomm.agents.collision import Mate
from mrcomm.agents.team_view import TeamView, near_numbers, near_numbers_numpy
from mrcomm.messaging import latest as latest_module
from mrcomm.messaging.latest import KEEP_LATEST_FROM, LatestMessages
from mrcomm.messaging.messages import PoseMsg
from mrcomm.ports import Received, StepBatch

from .fakes import pose_of

MEMBERS = KEEP_LATEST_FROM + 50
NAMES = np.array([f"robot_{s}" for s in range(MEMBERS)], dtype=object)
INDEX = {name: number for number, name in enumerate(NAMES.tolist())}


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


def _store() -> LatestMessages:
    return LatestMessages(NAMES, INDEX, ("x", "y"))


def _write(latest: LatestMessages, step: list[tuple[int, PoseMsg]], now: float) -> None:
    """The step's poses, all reaching receiver 0, written as the bus writes a batch."""
    messages = np.empty(len(step), dtype=object)
    messages[:] = [m for _, m in step]
    senders = np.array([s for s, _ in step], dtype=np.intp)
    columns = {f: np.array([getattr(m, f) for _, m in step]) for f in ("x", "y")}
    received = np.ones((len(step), 1), dtype=np.bool_)
    latest.write_step(messages, senders, np.array([0]), received, columns, now)


def _in_box(mates: Collection[Mate], x: float, y: float, reach: float) -> list[Mate]:
    """The mates within ``reach`` along both axes, as the callers of near() test it."""
    return [m for m in mates if -reach <= m.x - x <= reach and -reach <= m.y - y <= reach]


def test_without_a_store_every_known_mate_is_a_candidate() -> None:
    view = TeamView()
    view.hear_all([pose_of("robot_1", 0.0, 0.0), pose_of("robot_2", 90.0, 0.0)], 0.0, "")
    assert [m.robot for m in view.near(0.0, 0.0, 1.0, 0.0, None, 0.0)] == ["robot_1", "robot_2"]


def test_the_store_finds_the_near_mates_the_loop_finds() -> None:
    arrays, loop = TeamView(), TeamView()
    latest = _store()
    arrays.attach(latest, 0)
    rng = np.random.default_rng(7)
    checked = 0
    for now, step in enumerate(_steps(3)):
        _write(latest, step, float(now))
        loop.hear_all([m for _, m in step], float(now), "robot_0")
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
    latest = _store()
    arrays.attach(latest, 0)
    step = [(1, pose_of("robot_1", 10.0, 10.0)), (2, pose_of("robot_2", 12.5, 10.0))]
    _write(latest, step, 0.0)
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


def test_a_view_on_the_store_hears_nothing_itself() -> None:
    """Poses heard beside the store would leave the two apart: refused."""
    view = TeamView()
    view.attach(_store(), 0)
    with pytest.raises(RuntimeError, match="bus keeps"):
        view.hear(pose_of("robot_1", 0.0, 0.0), 0.0)


@pytest.mark.parametrize("block_entries", [1 << 20, 7])
def test_a_step_written_at_once_is_each_pose_written_in_turn(
    block_entries: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Many receivers, each reached by its own share of a step's poses: the arrays (and
    the order each receiver first heard its senders in) are those of writing every
    pose to every receiver it reached, message by message; also when the receivers
    are written a few at a time (as a team of thousands is)."""
    monkeypatch.setattr(latest_module, "_BLOCK_ENTRIES", block_entries)
    rng = np.random.default_rng(11)
    at_once, in_turn = _store(), _store()
    receivers = rng.choice(MEMBERS, size=40, replace=False).astype(np.intp)
    for now, step in enumerate(_steps(5)):
        senders = np.array([s for s, _ in step], dtype=np.intp)
        received = rng.random((len(step), len(receivers))) < 0.7
        received &= senders[:, None] != receivers[None, :]  # nobody hears itself
        messages = np.empty(len(step), dtype=object)
        messages[:] = [m for _, m in step]
        columns = {f: np.array([getattr(m, f) for _, m in step]) for f in ("x", "y")}
        at_once.write_step(messages, senders, receivers, received, columns, float(now))
        for row, column in zip(*np.nonzero(received), strict=True):
            in_turn.write(int(receivers[column]), int(senders[row]), step[row][1], float(now))
    assert (at_once.message == in_turn.message).all()
    assert (at_once.first == in_turn.first).all() and (at_once.heard_count > 0).any()
    assert (at_once.heard_count == in_turn.heard_count).all()
    for a, b in [(at_once.heard_at, in_turn.heard_at), *zip(
        at_once.columns.values(), in_turn.columns.values(), strict=True
    )]:  # fmt: skip
        assert np.array_equal(a, b, equal_nan=True)


def test_a_receivers_share_reads_as_its_messages() -> None:
    step = [(4, pose_of("robot_4", 1.0, 0.0)), (9, pose_of("robot_9", 2.0, 0.0))]
    senders = np.array([s for s, _ in step], dtype=np.intp)
    share = Received(StepBatch([m for _, m in step], senders, NAMES, INDEX), np.arange(2))
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
