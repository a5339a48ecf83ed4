"""Route repair (robot/repair.py): a way round mates, or back to the route, that
rejoins it ``repair_horizon`` ahead and keeps the rest; the whole route searched again
when less than that is left or the small window holds no way; off by default."""

from __future__ import annotations

import itertools
import math

import pytest

from mrcomm.ports import NavStatus
from mrcomm.robot import GridPlanner, RobotParams
from mrcomm.robot.follower import PathFollower
from mrcomm.robot.repair import repaired_route
from mrcomm.world.occupancy import OccupancyGrid
from tests.robot.robot_maps import RES, blank, make_base, ring, run

P = RobotParams()


def open_room() -> OccupancyGrid:
    return OccupancyGrid(blank(20.0, 8.0), RES)


def _disc_clear(
    waypoints: tuple[tuple[float, float], ...], mate: tuple[float, float], radius: float
) -> bool:
    """Every point of the polyline, sampled every 2 cm, is farther than ``radius``."""
    for (ax, ay), (bx, by) in itertools.pairwise(waypoints):
        steps = max(1, math.ceil(math.dist((ax, ay), (bx, by)) / 0.02))
        for k in range(steps + 1):
            t = k / steps
            if math.dist((ax + t * (bx - ax), ay + t * (by - ay)), mate) <= radius:
                return False
    return True


def test_ahead_measures_along_the_route_from_the_robot() -> None:
    route = PathFollower([(0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (9.0, 3.0)], P)
    assert route.ahead(0.0, 0.0, 2.0) == ((2.0, 0.0), [(4.0, 0.0), (4.0, 3.0), (9.0, 3.0)])
    assert route.ahead(0.0, 0.0, 5.0) == ((4.0, 1.0), [(4.0, 3.0), (9.0, 3.0)])
    (x, y), rest = route.ahead(0.0, 0.0, 11.5)  # type: ignore[misc]
    assert (x, y) == pytest.approx((8.5, 3.0)) and rest == [(9.0, 3.0)]
    assert route.ahead(0.0, 0.0, 12.5) is None  # 12 m left


def test_a_repair_goes_round_the_mate_and_keeps_the_rest_of_the_route() -> None:
    planner = GridPlanner(open_room(), P)
    route = PathFollower([(1.0, 2.0), (9.0, 2.0), (9.0, 6.0), (18.0, 6.0)], P)
    mate = (3.0, 2.0)
    repaired = repaired_route(planner, (1.0, 2.0), route, 4.0, [mate], None, None)
    assert repaired is not None
    waypoints = repaired.waypoints
    assert waypoints[0] == (1.0, 2.0)
    # It rejoins the route 4 m on and keeps the rest of it as it was.
    rejoin = waypoints.index((5.0, 2.0))
    assert waypoints[rejoin + 1 :] == ((9.0, 2.0), (9.0, 6.0), (18.0, 6.0))
    # The way to the rejoining point keeps clear of the mate's blocked disc.
    disc = 2 * P.radius + P.block_margin
    assert _disc_clear(waypoints[: rejoin + 1], mate, disc)
    lengths = itertools.pairwise(waypoints)
    assert repaired.length == pytest.approx(sum(math.dist(a, b) for a, b in lengths))
    # The whole route searched again would have gone straight for the goal instead.
    whole = planner.plan((1.0, 2.0), (18.0, 6.0), [mate])
    assert whole is not None and (9.0, 6.0) not in whole.waypoints


def test_less_than_the_horizon_left_is_no_repair() -> None:
    planner = GridPlanner(open_room(), P)
    route = PathFollower([(1.0, 2.0), (4.0, 2.0)], P)
    assert repaired_route(planner, (1.0, 2.0), route, 4.0, [(2.5, 2.0)], None, None) is None


def test_a_window_without_a_way_is_no_repair() -> None:
    """In the ring's top corridor, a mate fills the corridor: the way round is the
    bottom corridor, far outside the window around the robot and the rejoining point."""
    grid = ring()
    planner = GridPlanner(grid, P)
    base = make_base(grid, (0.75, 4.0, math.pi / 2), planner=planner)
    base.navigate_to(11.25, 4.0)
    route = PathFollower(base.path, P)
    assert repaired_route(planner, (0.75, 4.0), route, 4.0, [(3.0, 5.25)], None, None) is None


def test_a_base_with_a_horizon_goes_the_other_way_round_a_blocked_corridor() -> None:
    params = RobotParams(repair_horizon=4.0)
    base = make_base(ring(), (0.75, 4.0, math.pi / 2), params=params)
    base.navigate_to(11.25, 4.0)
    mate = (6.0, 5.25)
    (trace,) = run([base], 200.0, parked=lambda _t: [mate])
    assert base.status is NavStatus.SUCCEEDED
    assert base.replans >= 1
    assert min(y for _, x, y, _, _ in trace if 4.0 < x < 8.0) < 1.5


def test_a_base_with_a_horizon_repairs_round_a_mate_and_arrives() -> None:
    params = RobotParams(repair_horizon=4.0)
    grid = open_room()
    base = make_base(grid, (1.0, 2.0, 0.0), params=params)
    base.navigate_to(18.0, 6.0)
    base._follow(planner_path([(1.0, 2.0), (9.0, 2.0), (9.0, 6.0), (18.0, 6.0)]))
    mate = (4.0, 2.0)
    routes: list[tuple[int, tuple[tuple[float, float], ...]]] = []

    def parked(_t: float) -> list[tuple[float, float]]:
        routes.append((base.replans, base.path))  # as the last step left them
        return [mate]

    (trace,) = run([base], 200.0, parked=parked)
    assert base.status is NavStatus.SUCCEEDED
    # The first re-plan round the mate rejoined the route and kept its rest.
    first = next(path for replans, path in routes if replans == 1)
    assert first[-3:] == ((9.0, 2.0), (9.0, 6.0), (18.0, 6.0))
    assert min(math.dist(mate, (x, y)) for _, x, y, _, _ in trace) > 2 * P.radius + 0.1
    assert all(grid.is_free(x, y) for _, x, y, _, _ in trace)


def test_a_repair_rejoining_at_a_waypoint_does_not_repeat_it() -> None:
    planner = GridPlanner(open_room(), P)
    route = PathFollower([(1.0, 2.0), (5.0, 2.0), (5.0, 6.0)], P)
    repaired = repaired_route(planner, (1.0, 2.0), route, 4.0, [(3.0, 2.0)], None, None)
    assert repaired is not None
    assert repaired.waypoints.count((5.0, 2.0)) == 1
    assert repaired.waypoints[-2:] == ((5.0, 2.0), (5.0, 6.0))


@pytest.mark.parametrize("horizon", [0.0, 3.0])
def test_a_goal_asked_again_after_cancel_repairs_the_route_given_up(horizon: float) -> None:
    """Resuming after giving way: with a horizon the route is rejoined 3 m on and its
    rest kept; without, the whole route is searched again from where the robot is."""
    params = RobotParams(repair_horizon=horizon)
    grid = open_room()
    planner = GridPlanner(grid, params)
    base = make_base(grid, (1.0, 2.0, 0.0), params=params, planner=planner)
    route = [(1.0, 2.0), (9.0, 2.0), (9.0, 6.0), (18.0, 6.0)]
    # The route it was following (as a re-plan round a mate might have left it).
    base.navigate_to(18.0, 6.0)
    base._follow(planner_path(route))
    run([base], 2.0, stop_when_done=False)
    base.cancel()
    run([base], 2.0, stop_when_done=False)  # brakes to a stop
    here = (base.pose.x, base.pose.y)
    base.navigate_to(18.0, 6.0)
    assert base.status is NavStatus.ACTIVE
    if horizon:
        assert base.path[-3:] == ((9.0, 2.0), (9.0, 6.0), (18.0, 6.0))
        assert math.dist(base.path[0], here) < 1e-9
    else:
        fresh = planner.plan(here, (18.0, 6.0))
        assert fresh is not None and base.path == fresh.waypoints
        assert (9.0, 6.0) not in base.path


def test_another_goal_is_planned_whole() -> None:
    params = RobotParams(repair_horizon=3.0)
    grid = open_room()
    planner = GridPlanner(grid, params)
    base = make_base(grid, (1.0, 2.0, 0.0), params=params, planner=planner)
    base.navigate_to(18.0, 6.0)
    base._follow(planner_path([(1.0, 2.0), (9.0, 2.0), (9.0, 6.0), (18.0, 6.0)]))
    base.cancel()
    base.navigate_to(17.0, 6.0)
    fresh = planner.plan((base.pose.x, base.pose.y), (17.0, 6.0))
    assert fresh is not None and base.path == fresh.waypoints


def planner_path(waypoints: list[tuple[float, float]]):  # type: ignore[no-untyped-def]
    from mrcomm.robot.planner import PlannedPath
    from mrcomm.world.geometry import polyline_length

    return PlannedPath(tuple(waypoints), polyline_length(waypoints))


def test_the_horizon_is_a_checked_parameter() -> None:
    from mrcomm.errors import InputError

    with pytest.raises(InputError, match="repair_horizon"):
        RobotParams.from_mapping({"repair_horizon": -1.0})
    assert RobotParams().repair_horizon == 0.0
