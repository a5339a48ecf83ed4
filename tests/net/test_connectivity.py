"""The team's largest connected group: the graph search, its sampling over a run, and
the team-scale metrics of a whole mission."""

from __future__ import annotations

import numpy as np

from mrcomm.net.links import GROUP_PERIOD, LinkRecorder, LinkState, largest_group


def links(n: int, edges: list[tuple[int, int]], one_way: list[tuple[int, int]] = ()) -> np.ndarray:  # type: ignore[assignment]
    connected = np.eye(n, dtype=np.bool_)
    for a, b in edges:
        connected[a, b] = connected[b, a] = True
    for a, b in one_way:
        connected[a, b] = True
    return connected


def test_a_chain_is_one_group_through_its_middle() -> None:
    # 0 - 1 - 2 - 3 and 4 - 5: 0 and 3 are out of range of each other, linked by 1 and 2.
    assert largest_group(links(6, [(0, 1), (1, 2), (2, 3), (4, 5)])) == 4


def test_links_count_only_when_connected_both_ways() -> None:
    assert largest_group(links(3, [], one_way=[(0, 1), (1, 2)])) == 1
    assert largest_group(links(3, [(0, 1)], one_way=[(1, 2)])) == 2


def test_everyone_in_range_and_everyone_alone() -> None:
    assert largest_group(np.ones((5, 5), dtype=np.bool_)) == 5
    assert largest_group(np.eye(5, dtype=np.bool_)) == 1
    assert largest_group(np.zeros((0, 0), dtype=np.bool_)) == 0


def test_the_recorder_samples_the_group_of_robots_at_its_period() -> None:
    ids = ("r1", "r2", "r3", "r4", "assigner")
    recorder = LinkRecorder(ids, robots=4)
    together = links(5, [(0, 1), (1, 2), (2, 3), (3, 4)])
    apart = links(5, [(0, 1), (2, 4)])  # two pairs; the assigner does not count
    dt = 0.1
    for k in range(20):  # 1 s together, then 1 s apart
        connected = together if k < 10 else apart
        state = LinkState(ids, np.zeros((5, 5)), None, None, np.zeros((5, 5), bool), connected)
        recorder.record(state, dt, k * dt)
    times = [t for t, _ in recorder.largest_group]
    assert times == [0.0, 0.5, 1.0, 1.5] and GROUP_PERIOD == 0.5
    assert [size for _, size in recorder.largest_group] == [4, 4, 2, 2]
    assert recorder.connectivity() == {"largest_group_mean": 0.75, "largest_group_min": 0.5}


def test_no_sample_no_value() -> None:
    assert LinkRecorder(("r1", "assigner"), robots=1).connectivity() == {
        "largest_group_mean": None,
        "largest_group_min": None,
    }
