"""SimBase: reaching goals, limits, safety, re-planning around mates, stuck recovery,
determinism."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from mrcomm.ports import Base, NavStatus
from mrcomm.robot import GridPlanner, RobotParams
from tests.robot.robot_maps import dead_end, make_base, ring, run, sealed_rooms, two_rooms

P = RobotParams()
DT = 0.1


def min_wall_clearance(planner: GridPlanner, trace: list[tuple[float, ...]]) -> float:
    return min(planner.clearance(x, y) for _, x, y, _, _ in trace)


def test_is_a_base() -> None:
    base: Base = make_base(two_rooms(), (1.0, 1.0, 0.0))
    assert base.status is NavStatus.IDLE
    assert base.odometry_distance == 0.0
    assert base.speed == 0.0


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize(
    ("start", "goal"),
    [
        ((1.0, 1.0, 0.0), (9.0, 4.0)),
        ((9.0, 1.0, math.pi), (1.0, 4.5)),
        ((2.0, 4.0, -2.0), (2.5, 0.5)),
    ],
)
def test_reaches_goal_without_touching_walls(
    seed: int, start: tuple[float, float, float], goal: tuple[float, float]
) -> None:
    grid = two_rooms()
    base = make_base(grid, start, seed=seed)
    base.navigate_to(*goal)
    assert base.status is NavStatus.ACTIVE
    (trace,) = run([base], 120.0)
    assert base.status is NavStatus.SUCCEEDED
    assert base.pose.distance_to(*goal) < P.goal_tolerance
    assert base.true_pose.distance_to(*goal) < P.goal_tolerance + 0.1
    # The centre never enters an occupied cell, and the footprint never touches a wall.
    assert all(grid.is_free(x, y) for _, x, y, _, _ in trace)
    assert min_wall_clearance(base.planner, trace) >= P.radius
    assert base.bumps == 0
    # Odometry roughly agrees with the true distance travelled.
    true_dist = sum(math.dist(a[1:3], b[1:3]) for a, b in itertools.pairwise(trace))
    assert base.odometry_distance == pytest.approx(true_dist, rel=0.05)
    assert base.speed == 0.0


def test_motion_respects_speed_and_acceleration_limits() -> None:
    base = make_base(two_rooms(), (1.0, 1.0, math.pi))
    base.navigate_to(9.0, 4.0)
    (trace,) = run([base], 120.0)
    vs = [0.0] + [v for *_, v, _ in trace]
    ws = [0.0] + [w for *_, w in trace]
    assert max(abs(v) for v in vs) <= P.max_v + 1e-9
    assert max(abs(w) for w in ws) <= P.max_w + 1e-9
    assert max(abs(b - a) for a, b in itertools.pairwise(vs)) <= P.max_accel * DT + 1e-9
    assert max(abs(b - a) for a, b in itertools.pairwise(ws)) <= (P.max_ang_accel * DT + 1e-9)
    # It did reach full speed on the long legs, and turned in place at the start
    # (facing away from the goal).
    assert max(vs) > 0.95 * P.max_v
    first_moves = [(v, w) for _, _, _, v, w in trace[:5]]
    assert all(v == 0.0 and w != 0.0 for v, w in first_moves)


def test_unreachable_goal_aborts_at_once() -> None:
    base = make_base(sealed_rooms(), (1.0, 1.0, 0.0))
    base.navigate_to(9.0, 4.0)
    assert base.status is NavStatus.ABORTED
    base.update(DT, 0.0, [])
    assert base.true_pose == (1.0, 1.0, 0.0)


def test_cancel_brakes_to_a_stop_and_goes_idle() -> None:
    base = make_base(two_rooms(), (1.0, 2.5, 0.0))
    base.navigate_to(4.5, 2.5)
    run([base], 2.0, stop_when_done=False)
    assert base.speed > 0.3
    base.cancel()
    assert base.status is NavStatus.IDLE
    assert base.path == ()
    (trace,) = run([base], 2.0, stop_when_done=False)
    speeds = [v for *_, v, _ in trace]
    assert speeds[-1] == 0.0
    assert all(b <= a for a, b in itertools.pairwise(speeds))
    assert sum(1 for v in speeds if v > 0) <= math.ceil(P.max_v / (P.max_accel * DT))
    # Idle and stopped: updates change nothing (not even the estimate).
    pose = base.pose
    run([base], 1.0, stop_when_done=False)
    assert base.pose == pose


def test_route_is_the_plan_still_ahead_ending_at_the_goal() -> None:
    base = make_base(two_rooms(), (1.0, 4.2, 0.0))
    assert base.route == ()
    base.navigate_to(9.0, 4.2)  # through the door at (5, 2.5): corners on the way
    first = base.route
    assert first[-1] == base.goal and first == base.path[1:]
    run([base], 12.0, stop_when_done=False)  # through the door
    later = base.route
    # waypoints reached drop off the front; what is ahead stays the plan's own tail
    assert later[-1] == base.goal and len(later) < len(first)
    assert later == base.path[len(base.path) - len(later) :]
    assert math.dist(later[0], base.goal) < math.dist(first[0], base.goal)
    base.cancel()
    assert base.route == ()


def test_new_goal_replaces_current_one() -> None:
    base = make_base(two_rooms(), (1.0, 2.5, 0.0))
    base.navigate_to(9.0, 2.5)
    run([base], 3.0, stop_when_done=False)
    base.navigate_to(1.0, 4.0)
    assert base.goal == (1.0, 4.0)
    run([base], 60.0)
    assert base.status is NavStatus.SUCCEEDED
    assert base.pose.distance_to(1.0, 4.0) < P.goal_tolerance


def test_replans_around_robot_parked_in_corridor() -> None:
    grid = ring()
    base = make_base(grid, (0.75, 4.0, math.pi / 2))
    base.navigate_to(11.25, 4.0)
    # The first plan takes the short top corridor, where a mate is parked.
    assert max(y for _, y in base.path) > 4.5
    mate = (6.0, 5.25)
    (trace,) = run([base], 200.0, parked=lambda _t: [mate])
    assert base.status is NavStatus.SUCCEEDED
    assert base.replans >= 1
    assert base.recoveries == 0
    # It went round by the bottom corridor and never came near the mate.
    assert min(y for _, x, y, _, _ in trace if 4.0 < x < 8.0) < 1.5
    assert min(math.dist(mate, (x, y)) for _, x, y, _, _ in trace) > 2 * P.radius + 0.3
    assert all(grid.is_free(x, y) for _, x, y, _, _ in trace)


def test_no_replan_without_mates_in_range() -> None:
    base = make_base(ring(), (0.75, 4.0, math.pi / 2))
    base.navigate_to(11.25, 4.0)
    run([base], 200.0, parked=lambda _t: [(6.0, 1.0)])  # in the other corridor
    assert base.status is NavStatus.SUCCEEDED
    assert base.replans == 0


def _stuck_in_dead_end(mate_leaves_at: float) -> tuple[object, list[tuple[float, ...]]]:
    base = make_base(dead_end(), (1.0, 1.5, 0.0), seed=3)
    base.navigate_to(9.0, 1.5)
    mate = (5.0, 1.5)
    (trace,) = run([base], 120.0, parked=lambda t: [mate] if t < mate_leaves_at else [])
    return base, trace


def test_waits_for_blocking_mate_then_recovers_by_reversing() -> None:
    base, trace = _stuck_in_dead_end(mate_leaves_at=20.0)
    assert base.status is NavStatus.SUCCEEDED  # type: ignore[attr-defined]
    assert base.recoveries == 1  # type: ignore[attr-defined]
    xs = [x for _, x, _, _, _ in trace]
    vs = [v for _, _, _, v, _ in trace]
    # It held at a distance from the mate (no path round it), never touching it.
    i0 = next(i for i, v in enumerate(vs) if v < 0)  # the reversal starts
    held = xs[i0 - 1]
    assert 5.0 - P.hold_distance - 0.15 < held < 5.0 - 2 * P.radius - P.block_margin
    assert all(v == 0.0 for v in vs[i0 - 20 : i0])  # waiting, then stuck
    # Then backed off about the reverse distance (measured by odometry), and resumed.
    i1 = next(i for i in range(i0, len(vs)) if vs[i] >= 0)
    backed = held - min(xs[i0 : i1 + 1])
    assert backed == pytest.approx(P.reverse_distance, abs=0.05)
    assert max(xs[i1:]) > 8.8
    assert any(v < 0 for _, _, _, v, _ in trace)


def test_recovery_that_keeps_failing_aborts() -> None:
    base, trace = _stuck_in_dead_end(mate_leaves_at=math.inf)
    assert base.status is NavStatus.ABORTED  # type: ignore[attr-defined]
    assert base.recoveries == P.max_recoveries + 1  # type: ignore[attr-defined]
    assert max(x for _, x, _, _, _ in trace) < 5.0 - 2 * P.radius


@pytest.mark.parametrize("stale", [False, True])
def test_two_robots_never_overlap(stale: bool) -> None:
    # Head-on through the single narrow door, with no agent-level collision avoidance:
    # whatever happens (wait, recover, abort), the footprints never overlap and no
    # one enters a wall.
    grid = two_rooms()
    params = RobotParams()
    planner = GridPlanner(grid, params)
    a = make_base(grid, (2.0, 2.5, 0.0), seed=1, planner=planner, robot_id="robot_1")
    b = make_base(grid, (8.0, 2.5, math.pi), seed=2, planner=planner, robot_id="robot_2")
    a.navigate_to(8.0, 2.4)
    b.navigate_to(2.0, 2.6)
    ta, tb = run([a, b], 150.0, stale=stale)
    gaps = [math.dist(p[1:3], q[1:3]) for p, q in zip(ta, tb, strict=False)]
    assert min(gaps) >= 2 * P.radius
    assert all(grid.is_free(x, y) for _, x, y, _, _ in ta + tb)
    assert {a.status, b.status} <= {NavStatus.SUCCEEDED, NavStatus.ABORTED}


def test_robots_crossing_in_open_room_both_arrive() -> None:
    grid = two_rooms()
    planner = GridPlanner(grid, P)
    a = make_base(grid, (1.0, 1.0, 0.0), seed=1, planner=planner)
    b = make_base(grid, (4.0, 4.0, math.pi), seed=2, planner=planner)
    a.navigate_to(4.0, 4.0 - 0.6)
    b.navigate_to(1.0, 1.0 + 0.6)
    ta, tb = run([a, b], 120.0)
    assert a.status is NavStatus.SUCCEEDED
    assert b.status is NavStatus.SUCCEEDED
    assert min(math.dist(p[1:3], q[1:3]) for p, q in zip(ta, tb, strict=False)) >= 2 * P.radius


def _mission(seed: int) -> list[list[tuple[float, ...]]]:
    grid = two_rooms()
    planner = GridPlanner(grid, P)
    a = make_base(grid, (1.0, 1.0, 0.0), seed=seed, planner=planner)
    b = make_base(grid, (1.0, 4.0, 0.0), seed=seed + 100, planner=planner)
    a.navigate_to(9.0, 4.0)
    b.navigate_to(9.0, 1.0)
    return run([a, b], 120.0)  # type: ignore[return-value]


def test_same_seed_same_trajectory() -> None:
    first = _mission(5)
    assert first == _mission(5)
    assert first != _mission(6)


def test_estimate_and_odometry_are_noisy_but_close() -> None:
    base = make_base(two_rooms(), (1.0, 1.0, 0.0), seed=9)
    base.navigate_to(9.0, 4.0)
    errors = []
    for k in range(400):
        base.update(DT, k * DT, [])
        t, e = base.true_pose, base.pose
        errors.append(math.dist((t.x, t.y), (e.x, e.y)))
    assert 0.0 < np.mean(errors) < 4 * P.loc_position_noise
    odo = base.odometry_pose
    assert odo != base.true_pose
    assert math.dist((odo.x, odo.y), (base.true_pose.x, base.true_pose.y)) < 0.5


def test_mate_driving_away_ahead_is_followed_not_replanned_around() -> None:
    grid = ring()
    base = make_base(grid, (1.0, 5.25, 0.0))
    base.navigate_to(8.0, 5.25)

    def mate(t: float) -> list[tuple[float, float]]:
        return [(min(2.0 + 0.3 * t, 11.5), 5.25)]  # slower than us, then past our goal

    (trace,) = run([base], 120.0, parked=mate)
    assert base.status is NavStatus.SUCCEEDED
    assert base.recoveries == 0
    assert base.replans == 0
    assert trace[-1][0] > (8.0 - 2.0) / 0.3  # it could not overtake: it followed
    gaps = [math.dist((x, y), mate(t - DT)[0]) for t, x, y, _, _ in trace]
    assert min(gaps) > 2 * P.radius + 0.05
    assert min(y for _, _, y, _, _ in trace) > 4.5  # stayed in the top corridor


def test_waits_without_recovery_for_mate_standing_on_goal() -> None:
    base = make_base(dead_end(), (1.0, 1.5, 0.0))
    base.navigate_to(5.0, 1.5)
    mate = (5.0, 1.5)
    run([base], 40.0, parked=lambda _t: [mate], stop_when_done=False)
    assert base.status is NavStatus.ACTIVE
    assert base.waiting
    assert base.recoveries == 0
    assert base.replans <= 1
    assert 2 * P.radius < base.true_pose.distance_to(*mate) < P.hold_distance + 0.05
    run([base], 20.0)  # the mate leaves
    assert base.status is NavStatus.SUCCEEDED
    assert not base.waiting


def test_recovery_does_not_reverse_into_a_wall() -> None:
    grid = dead_end()
    base = make_base(grid, (0.45, 1.5, 0.0))  # back 0.4 m from the end wall
    base.navigate_to(9.0, 1.5)
    (trace,) = run([base], 60.0, parked=lambda _t: [(1.4, 1.5)])
    assert base.recoveries >= 1
    assert min(grid.clearance(x, y) for _, x, y, _, _ in trace) >= P.radius
    assert base.bumps == 0
    assert -math.pi <= base.true_pose.theta < math.pi


TWO = two_rooms()
TWO_PLANNER = GridPlanner(TWO, P)


@settings(max_examples=15, deadline=None)
@given(
    st.tuples(st.floats(0.5, 9.5), st.floats(0.5, 4.5), st.floats(-math.pi, math.pi)),
    st.tuples(st.floats(0.5, 9.5), st.floats(0.5, 4.5)),
    st.integers(0, 1000),
)
def test_any_reachable_goal_is_reached_safely(
    start: tuple[float, float, float], goal: tuple[float, float], seed: int
) -> None:
    assume(TWO_PLANNER.is_free(start[0], start[1]))
    base = make_base(TWO, start, seed=seed, planner=TWO_PLANNER)
    base.navigate_to(*goal)
    if TWO_PLANNER.snap(*goal) is None:
        assert base.status is NavStatus.ABORTED
        return
    (trace,) = run([base], 120.0)
    assert base.status is NavStatus.SUCCEEDED
    target = base.goal
    assert target is not None
    assert base.pose.distance_to(*target) < P.goal_tolerance
    assert min(TWO_PLANNER.clearance(x, y) for _, x, y, _, _ in trace) >= P.radius


def test_goal_in_inflated_zone_is_reached_at_its_snapped_point() -> None:
    grid = two_rooms()
    base = make_base(grid, (1.0, 1.0, 0.0))
    base.navigate_to(4.85, 1.0)  # 0.15 m from the wall: the centre cannot get there
    target = base.goal
    assert target is not None and target != (4.85, 1.0)
    assert math.dist(target, (4.85, 1.0)) <= P.max_snap + 0.1
    run([base], 60.0)
    assert base.status is NavStatus.SUCCEEDED
    assert base.goal == target
    assert base.pose.distance_to(*target) < P.goal_tolerance
    base.cancel()
    assert base.goal is None


def test_contact_guard_holds_even_when_navigation_is_badly_misled() -> None:
    # A localisation error of ~0.3 m misleads the controller into walls and mates; the
    # guard on the true pose still refuses every motion into them (it bumps instead).
    noisy = RobotParams(loc_position_noise=0.3, loc_noise_time_constant=20.0)
    grid = two_rooms()
    planner = GridPlanner(grid, noisy)
    bumps = 0
    for seed in range(3):
        a = make_base(grid, (1.0, 1.0, 0.0), seed=seed, planner=planner, params=noisy)
        b = make_base(grid, (4.0, 1.3, 0.0), seed=seed + 50, planner=planner, params=noisy)
        a.navigate_to(9.0, 4.0)
        b.navigate_to(1.0, 4.0)
        ta, tb = run([a, b], 90.0, stale=True)
        for tr in (ta, tb):
            assert min(planner.clearance(x, y) for _, x, y, _, _ in tr) >= noisy.radius
        gaps = [math.dist(p[1:3], q[1:3]) for p, q in zip(ta, tb, strict=False)]
        assert min(gaps) >= 2 * noisy.radius
        bumps += a.bumps + b.bumps
    assert bumps > 0


def test_stops_short_of_a_mate_that_appears_right_ahead() -> None:
    # A mate steps out 0.45 m in front of a robot at full speed: braking alone would
    # take 0.125 m, so without the contact guard the footprints would overlap.
    grid = ring()
    base = make_base(grid, (1.0, 5.25, 0.0))
    base.navigate_to(11.0, 5.25)
    appeared: list[tuple[float, float]] = []

    def mate(t: float) -> list[tuple[float, float]]:
        if t >= 4.0 and not appeared:
            appeared.append((base.true_pose.x + 0.45, base.true_pose.y))
        return appeared

    (trace,) = run([base], 8.0, parked=mate, stop_when_done=False)
    assert appeared
    assert trace[35][3] == pytest.approx(P.max_v, abs=0.01)  # full speed before the mate appeared
    gaps = [math.dist((x, y), appeared[0]) for t, x, y, _, _ in trace if t > 4.0]
    assert min(gaps) >= 2 * P.radius
    assert base.bumps > 0
