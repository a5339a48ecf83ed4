"""GridPlanner: paths through narrow doors, never through walls; no path -> None;
snapping; temporary obstacles."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mrcomm.robot.params import RobotParams
from mrcomm.robot.planner import GridPlanner, PlanMemo, PlannedPath
from mrcomm.world.occupancy import OccupancyGrid
from tests.robot.robot_maps import dead_end, ring, sealed_rooms, two_rooms

P = RobotParams()


def assert_safe(path: PlannedPath, grid: OccupancyGrid, radius: float = P.radius) -> None:
    """Every segment has line of sight on the map inflated by the robot's radius (the
    footprint never overlaps a wall anywhere along the polyline)."""
    body = grid.inflated(radius)
    pts = np.array(path.waypoints)
    assert body.line_of_sight_many(pts[:-1], pts[1:]).all()


def test_path_through_narrow_door() -> None:
    grid = two_rooms(door=0.8)
    path = GridPlanner(grid, P).plan((1.0, 1.0), (9.0, 4.0))
    assert path is not None
    assert path.waypoints[0] == (1.0, 1.0)
    assert path.goal == (9.0, 4.0)
    assert_safe(path, grid)
    # It crosses the dividing wall (x = 5.0..5.1) within the door (y = 2.1..2.9).
    pts = np.array(path.waypoints)
    for a, b in itertools.pairwise(pts):
        if a[0] < 5.05 <= b[0]:
            y = a[1] + (b[1] - a[1]) * (5.05 - a[0]) / (b[0] - a[0])
            assert 2.1 + P.inflation_radius - 0.06 < y < 2.9 - P.inflation_radius + 0.06
    assert path.length == pytest.approx(sum(math.dist(a, b) for a, b in itertools.pairwise(pts)))
    assert path.length < 1.1 * (math.dist((1, 1), (5.05, 2.5)) + math.dist((5.05, 2.5), (9, 4)))


def test_door_narrower_than_robot_has_no_path() -> None:
    planner = GridPlanner(two_rooms(door=0.4), P)
    assert planner.plan((1.0, 1.0), (9.0, 4.0)) is None
    assert planner.plan((1.0, 1.0), (4.0, 4.0)) is not None


def test_no_path_between_sealed_rooms() -> None:
    assert GridPlanner(sealed_rooms(), P).plan((1.0, 1.0), (9.0, 4.0)) is None


def test_goal_inside_wall_is_unreachable_and_near_wall_is_snapped() -> None:
    grid = two_rooms()
    planner = GridPlanner(grid, P)
    near = planner.plan((1.0, 1.0), (4.85, 1.0))  # 0.15 m from the wall: inflated zone
    assert near is not None
    gx, gy = near.goal
    assert math.dist((gx, gy), (4.85, 1.0)) <= P.max_snap + planner.resolution
    assert planner.is_free(gx, gy)
    assert_safe(near, grid)
    assert planner.plan((1.0, 1.0), (50.0, 50.0)) is None  # off the map
    # Deep inside the 1 m thick wall of the corridor map: nothing free within max_snap.
    assert GridPlanner(dead_end(), P).plan((1.0, 1.5), (5.0, 0.3)) is None


def test_start_in_inflated_zone_is_snapped() -> None:
    grid = two_rooms()
    planner = GridPlanner(grid, P)
    path = planner.plan((0.2, 0.2), (3.0, 3.0))
    assert path is not None
    assert path.waypoints[0] == (0.2, 0.2)
    assert planner.is_free(*path.waypoints[1])
    assert_safe(path, grid, radius=0.1)


def test_temporary_obstacle_forces_other_route() -> None:
    grid = ring()
    planner = GridPlanner(grid, P)
    start, goal = (0.75, 4.0), (11.25, 4.0)
    free = planner.plan(start, goal)
    assert free is not None
    assert max(y for _, y in free.waypoints) > 4.5  # the short way: top corridor
    mate = (6.0, 5.25)
    around = planner.plan(start, goal, obstacles=[mate])
    assert around is not None
    assert min(y for _, y in around.waypoints) < 1.5  # the long way: bottom corridor
    assert around.length > free.length
    assert_safe(around, grid)
    pts = np.array(around.waypoints)
    # No segment passes near the mate.
    for a, b in itertools.pairwise(pts):
        t = np.clip(np.dot(np.subtract(mate, a), b - a) / np.dot(b - a, b - a), 0, 1)
        assert math.dist(mate, a + t * (b - a)) > 2 * P.radius + P.block_margin


def test_obstacle_on_only_route_means_no_path_and_start_disc_is_ignored() -> None:
    planner = GridPlanner(dead_end(), P)
    assert planner.plan((1.0, 1.5), (9.0, 1.5), obstacles=[(5.0, 1.5)]) is None
    # A mate right next to the start does not lock the robot in its own cell.
    path = planner.plan((1.0, 1.5), (0.6, 1.5), obstacles=[(1.3, 1.5)])
    assert path is not None
    # A mate standing on the goal: no path.
    assert planner.plan((1.0, 1.5), (9.0, 1.5), obstacles=[(9.0, 1.5)]) is None


def test_path_keeps_to_corridor_centre() -> None:
    # Wall cost: in the 1 m corridor the path runs along the centre line, not along
    # the edge of the inflated zone.
    path = GridPlanner(dead_end(), P).plan((1.0, 1.3), (9.0, 1.7))
    assert path is not None
    mids = [y for x, y in path.waypoints if 2.0 < x < 8.0]
    assert all(abs(y - 1.5) < 0.11 for y in mids)


def test_clearance_lookup_matches_distance_field() -> None:
    grid = two_rooms()
    planner = GridPlanner(grid, P)
    rng = np.random.default_rng(0)
    for x, y in rng.uniform([0, 0], [10, 5], size=(200, 2)):
        assert planner.clearance(x, y) == pytest.approx(grid.clearance(x, y), abs=1e-6)
    assert planner.clearance(-1.0, 2.0) == 0.0


points = st.tuples(st.floats(0.3, 9.7), st.floats(0.3, 4.7))


@settings(max_examples=60, deadline=None)
@given(points, points)
def test_paths_never_cross_walls(start: tuple[float, float], goal: tuple[float, float]) -> None:
    path = PLANNER_TWO_ROOMS.plan(start, goal)
    if path is None:
        # Only when start or goal cannot be snapped out of the wall's inflated zone.
        assert PLANNER_TWO_ROOMS.snap(*start) is None or PLANNER_TWO_ROOMS.snap(*goal) is None
        return
    # The first leg may start inside the inflated zone (the robot is where it is);
    # from the first free cell on, the footprint clears every wall.
    tail = PlannedPath(path.waypoints[1:], 0.0) if not PLANNER_TWO_ROOMS.is_free(*start) else path
    if len(tail.waypoints) >= 2:
        assert_safe(tail, TWO_ROOMS)


TWO_ROOMS = two_rooms()
PLANNER_TWO_ROOMS = GridPlanner(TWO_ROOMS, P)


def test_a_memo_answers_a_repeated_search_as_the_search_would() -> None:
    """A robot's plan memo: asked again from the same planning cell to the same goal cell
    (a robot resuming where it paused), or around mates that block the same cells (a
    robot held by mates that do not move), it gives the path a search gives, without
    one; another start cell, other costs or other blocked cells search again; a goal
    with no path stays without one."""
    planner = GridPlanner(two_rooms(door=0.8), P)
    searches: list[int] = []
    search = planner._search

    def counted(*args: object, **kwargs: object) -> object:
        searches.append(1)
        return search(*args, **kwargs)  # type: ignore[arg-type]

    planner._search = counted  # type: ignore[assignment, method-assign]
    memo = PlanMemo()
    first = planner.plan((1.0, 1.0), (9.0, 4.0), memo=memo)
    again = planner.plan((1.01, 1.01), (9.0, 4.0), memo=memo)  # the same planning cell
    assert len(searches) == 1
    assert again == planner.plan((1.01, 1.01), (9.0, 4.0))  # as a search finds it
    assert first is not None and again is not None and again.waypoints[0] == (1.01, 1.01)
    assert len(searches) == 2
    planner.plan((2.0, 1.0), (9.0, 4.0), memo=memo)  # another start cell
    assert len(searches) == 3
    noisy = planner.tie_break_weights(np.random.default_rng(1), 0.5)
    planner.plan((2.0, 1.0), (9.0, 4.0), weights=noisy, memo=memo)  # other costs
    assert len(searches) == 4
    # Around mates: the same blocked cells are answered from the memo, other ones (a
    # mate moved) are searched; the search without mates stays remembered meanwhile.
    mate = [(3.5, 2.0)]  # in the way, in the first room
    around = planner.plan((2.0, 1.0), (9.0, 4.0), obstacles=mate, weights=noisy, memo=memo)
    assert around is not None and len(searches) == 5
    assert planner.plan((2.0, 1.0), (9.0, 4.0), obstacles=mate, weights=noisy, memo=memo) == around
    assert len(searches) == 5
    assert around == planner.plan((2.0, 1.0), (9.0, 4.0), obstacles=mate, weights=noisy)
    assert len(searches) == 6
    moved = [(3.5, 2.6)]
    planner.plan((2.0, 1.0), (9.0, 4.0), obstacles=moved, weights=noisy, memo=memo)
    assert len(searches) == 7
    planner.plan((2.0, 1.0), (9.0, 4.0), weights=noisy, memo=memo)
    assert len(searches) == 7
    # A mate in the only door: no path, remembered as such.
    door = [(5.05, 2.5)]
    assert planner.plan((2.0, 1.0), (9.0, 4.0), obstacles=door, memo=memo) is None
    assert planner.plan((2.0, 1.0), (9.0, 4.0), obstacles=door, memo=memo) is None
    assert len(searches) == 8
    sealed = GridPlanner(sealed_rooms(), P)
    none = PlanMemo()
    assert sealed.plan((1.0, 1.0), (9.0, 4.0), memo=none) is None
    assert sealed.plan((1.0, 1.0), (9.0, 4.0), memo=none) is None
