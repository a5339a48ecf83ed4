"""LinkModel bookkeeping: per-pair values spread into matrices, a hosted node shares its
host's links, and rays are re-cast only when a link's line of sight may have changed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mrcomm.net.links import LinkModel
from mrcomm.net.network import AdHoc, AdHocParams
from mrcomm.net.signal.bundled import default_model
from mrcomm.net.signal.table import RssiTable
from mrcomm.net.signal_thresholds import ModelThreshold
from mrcomm.net.thresholds import DistanceThreshold, PairLayout
from mrcomm.world.occupancy import OccupancyGrid


def test_pair_layout_spreads_one_value_per_pair_symmetrically() -> None:
    layout = PairLayout(3)
    first, second = layout.ends
    assert list(zip(first.tolist(), second.tolist(), strict=True)) == [(0, 1), (0, 2), (1, 2)]
    assert layout.count == 3
    m = layout.matrix([1.0, 2.0, 3.0], -1.0)
    np.testing.assert_array_equal(m, [[-1, 1, 2], [1, -1, 3], [2, 3, -1]])
    # The order of a larger team's pairs is the nested loops' (a < b, row by row).
    big = PairLayout(40)
    expected = [(a, b) for a in range(40) for b in range(a + 1, 40)]
    assert list(zip(*(e.tolist() for e in big.ends), strict=True)) == expected


def test_a_large_team_without_rays_holds_nothing_per_pair() -> None:
    """Beyond ARRAY_PAIRS pairs a link model that casts no rays takes its distances as
    one matrix: no pair index, no per-pair cast state (a 10,000-robot team would hold
    ~5 GB of it)."""
    ids = tuple(f"r{i}" for i in range(20))  # 190 pairs
    model = LinkModel(ids, _room(), AdHoc(AdHocParams()), DistanceThreshold(4.0))
    assert model._first.size == 0 and model._cast_from.size == 0
    assert model.layout._ends is None and model.layout._gather is None
    xy = np.column_stack([np.linspace(0.5, 9.5, 20), np.full(20, 3.5)])
    state = model.update(xy, 0.0)
    assert state.distance[0, 19] == pytest.approx(9.0)
    assert model.layout._gather is None


def _room() -> OccupancyGrid:
    occupied = np.zeros((80, 200), dtype=bool)
    occupied[:60, 99:101] = True  # a wall across x = 5 m, open above y = 3 m
    return OccupancyGrid(occupied, 0.05)


@pytest.fixture(scope="module")
def table() -> RssiTable:
    return RssiTable.from_model(default_model())


def test_a_hosted_node_copies_its_hosts_row_and_column(table: RssiTable) -> None:
    grid = _room()
    ids = ("a", "b", "c", "host")
    xy = np.array([[1.0, 1.0], [4.0, 1.0], [6.0, 1.5], [math.nan, math.nan]])
    aliased = LinkModel(
        ids, grid, AdHoc(AdHocParams()), ModelThreshold(table), aliases={"host": "b"}
    )
    state = aliased.update(xy, 0.0)
    # The same as evaluating "host" at b's position as a node of its own.
    explicit = LinkModel(ids, grid, AdHoc(AdHocParams()), ModelThreshold(table))
    plain = explicit.update(np.array([*xy[:3], xy[1]]), 0.0)
    assert aliased.evaluated_ids == ("a", "b", "c")
    for field in ("distance", "rssi", "line_of_sight", "warning", "connected"):
        got, want = getattr(state, field), getattr(plain, field)
        # b <-> host: distance 0, so the explicit model has a diagonal-like entry there.
        off = ~np.eye(4, dtype=bool)
        off[1, 3] = off[3, 1] = False
        np.testing.assert_array_equal(got[off], want[off], err_msg=field)
    assert state.distance[1, 3] == 0.0 and not state.warning[1, 3] and state.connected[1, 3]
    assert not state.line_of_sight[1, 2]  # b and c see each other through no wall
    assert state.line_of_sight[0, 1] and state.warning[1, 2]


def test_rays_are_recast_only_when_line_of_sight_may_have_changed(table: RssiTable) -> None:
    grid = _room()
    model = LinkModel(("a", "b"), grid, AdHoc(AdHocParams()), ModelThreshold(table))
    # In sight, 2 m apart in open space (clearance to the wall ~ 1 m): a 5 cm step
    # of both ends keeps the old answer; standing still never re-casts.
    model.update(np.array([[1.0, 2.0], [3.0, 2.0]]), 0.0)
    model.update(np.array([[1.05, 2.0], [3.05, 2.0]]), 0.1)
    model.update(np.array([[1.05, 2.0], [3.05, 2.0]]), 0.2)
    assert model.casts == 1
    # Behind the wall: re-cast after los_refresh (0.25 m) of motion, not before.
    model.update(np.array([[4.0, 1.0], [6.0, 1.0]]), 0.3)
    assert model.casts == 2
    model.update(np.array([[4.0, 1.2], [6.0, 1.0]]), 0.4)
    assert model.casts == 2
    model.update(np.array([[4.0, 1.3], [6.0, 1.0]]), 0.5)
    assert model.casts == 3
    # Out of the AH range: obstructed without a cast.
    state = model.update(np.array([[0.5, 1.0], [9.0, 1.0]]), 0.6)
    assert model.casts == 3 and state.line_of_sight is not None
    assert not state.line_of_sight[0, 1] and not state.connected[0, 1]


def test_no_ray_is_cast_for_a_threshold_without_signal_model() -> None:
    grid = _room()
    model = LinkModel(("a", "b"), grid, AdHoc(AdHocParams()), DistanceThreshold(4.0))
    state = model.update(np.array([[4.0, 1.0], [6.0, 1.0]]), 0.0)
    assert model.casts == 0 and state.line_of_sight is None and state.rssi is None


def test_link_state_intervals_per_pair() -> None:
    """Each robot pair's warning / out-of-range intervals, the worse direction counting,
    open intervals closed at the end, connected time not listed."""
    import numpy as np

    from mrcomm.net.links import LinkRecorder, LinkState

    ids = ("a", "b", "c")
    recorder = LinkRecorder(ids, robots=3)
    ok = np.ones((3, 3), dtype=bool)
    calm = np.zeros((3, 3), dtype=bool)

    def step(now: float, warning: np.ndarray, connected: np.ndarray) -> None:
        state = LinkState(ids, np.zeros((3, 3)), None, None, warning, connected)
        recorder.record(state, 0.5, now)

    warn_ab = calm.copy()
    warn_ab[0, 1] = True  # one direction is enough
    cut_bc = ok.copy()
    cut_bc[2, 1] = False
    step(0.0, calm, ok)
    step(0.5, warn_ab, ok)
    step(1.0, warn_ab, cut_bc)
    step(1.5, calm, cut_bc)
    step(2.0, calm, ok)
    step(2.5, warn_ab, ok)
    assert recorder.state_intervals(end=3.0) == [
        ("a", "b", "warning", 0.5, 1.5),
        ("b", "c", "out of range", 1.0, 2.0),
        ("a", "b", "warning", 2.5, 3.0),
    ]
    # Time in warning agrees with the per-pair summary.
    assert recorder.summaries()["a->b"]["time_in_warning"] == 1.5
