"""Run-to-run variation (robot/variation.py, noise.AmclError): each mechanism on its own
— speed factor, start delay, AMCL-like error with drift and jumps, planner tie-breaks —
and the per-robot seeding."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mrcomm.ports import NavStatus
from mrcomm.robot import GridPlanner, RobotParams, SimBase
from mrcomm.robot.noise import AmclError, LocalisationError, NormalStream
from mrcomm.robot.variation import (
    RobotDraws,
    RobotVariation,
    VariationParams,
    draw_robot,
    robot_variations,
)
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid
from tests.robot.robot_maps import RES, blank, fill, run

REALISTIC = VariationParams(variation="realistic")
#: Every mechanism off but the profile on: a base that differs only where a test says.
QUIET = VariationParams(
    variation="realistic",
    loc_position_sigma=0.0,
    loc_heading_sigma=0.0,
    heading_drift_sigma=0.0,
    jump_rate=0.0,
    speed_sigma=0.0,
    start_delay_max=0.0,
    planner_tie_noise=0.0,
)


def corridor() -> OccupancyGrid:
    return OccupancyGrid(blank(24.0, 3.0), RES)


def varied_base(
    grid: OccupancyGrid,
    start: tuple[float, float, float],
    params: VariationParams = QUIET,
    draws: RobotDraws | None = None,
    seed: int = 0,
    planner: GridPlanner | None = None,
) -> SimBase:
    planner = planner or GridPlanner(grid, RobotParams())
    draws = draws or RobotDraws(1.0, 0.0)
    variation = RobotVariation(params, draws, np.random.default_rng(seed + 100), None)
    return SimBase(
        "robot_1",
        grid,
        planner,
        Pose(*start),
        RobotParams(),
        np.random.default_rng(seed),
        variation,
    )


def time_to_goal(base: SimBase, goal: tuple[float, float], limit: float = 200.0) -> float:
    base.navigate_to(*goal)
    (trace,) = run([base], limit)
    assert base.status is NavStatus.SUCCEEDED
    return trace[-1][0]


@pytest.mark.parametrize("factor", [0.8, 1.15])
def test_speed_factor_scales_a_straight_traversal(factor: float) -> None:
    grid = corridor()
    nominal = time_to_goal(varied_base(grid, (1.0, 1.5, 0.0)), (23.0, 1.5))
    scaled_base = varied_base(grid, (1.0, 1.5, 0.0), draws=RobotDraws(factor, 0.0))
    scaled = time_to_goal(scaled_base, (23.0, 1.5))
    assert scaled_base.speed_factor == factor
    assert scaled_base.params.max_v == pytest.approx(RobotParams().max_v * factor)
    # 22 m at 0.5 m/s: the time scales with 1/factor (acceleration phases are short).
    assert scaled / nominal == pytest.approx(1.0 / factor, rel=0.03)


def test_start_delay_holds_the_robot_then_it_drives() -> None:
    base = varied_base(corridor(), (1.0, 1.5, 0.0), draws=RobotDraws(1.0, 3.0))
    assert base.start_delay == 3.0
    base.navigate_to(10.0, 1.5)
    (trace,) = run([base], 60.0)
    moved = [t for t, x, *_ in trace if x > 1.0 + 1e-9]
    assert min(moved) > 3.0
    assert base.status is NavStatus.SUCCEEDED


def test_per_run_draws_stay_in_bounds_and_spread_as_configured() -> None:
    p = REALISTIC
    draws = [draw_robot(p, 7, f"robot_{i}") for i in range(4000)]
    factors = np.array([d.speed_factor for d in draws])
    delays = np.array([d.start_delay for d in draws])
    assert factors.min() >= p.speed_min and factors.max() <= p.speed_max
    assert np.mean(factors) == pytest.approx(1.0, abs=0.01)
    assert np.std(factors) == pytest.approx(p.speed_sigma, rel=0.1)  # clipping is rare
    assert delays.min() >= 0.0 and delays.max() <= p.start_delay_max
    assert np.mean(delays) == pytest.approx(p.start_delay_max / 2, rel=0.05)


def test_each_robot_has_its_own_streams(s1_resources) -> None:  # type: ignore[no-untyped-def]
    planner = s1_resources.planner
    two = robot_variations(REALISTIC, 5, ["a", "b"], planner)
    three = robot_variations(REALISTIC, 5, ["a", "b", "c"], planner)
    assert two["a"] is not None and three["a"] is not None
    assert two["a"].draws == three["a"].draws  # adding a robot changes no other's draws
    assert two["a"].draws != two["b"].draws
    assert robot_variations(REALISTIC, 6, ["a"], planner)["a"] != two["a"]


def test_none_profile_draws_nothing(s1_resources) -> None:  # type: ignore[no-untyped-def]
    assert robot_variations(VariationParams(), 5, ["a", "b"], s1_resources.planner) == {
        "a": None,
        "b": None,
    }
    assert not VariationParams().active


def amcl(seed: int, params: VariationParams = REALISTIC) -> AmclError:
    p = params
    return AmclError(
        NormalStream(np.random.default_rng(seed)),
        p.loc_position_sigma,
        p.loc_heading_sigma,
        p.loc_time_constant,
        np.random.default_rng(seed + 1),
        drift_sigma=p.heading_drift_sigma,
        drift_tau=p.heading_drift_time_constant,
        jump_rate=p.jump_rate,
        jump_sigma=p.jump_sigma,
        jump_heading_sigma=p.jump_heading_sigma,
    )


def test_amcl_without_drift_and_jumps_is_the_base_error() -> None:
    quiet = REALISTIC.model_copy(update={"heading_drift_sigma": 0.0, "jump_rate": 0.0})
    a = amcl(3, quiet)
    b = LocalisationError(NormalStream(np.random.default_rng(3)), 0.03, 0.02, 3.0)
    for _ in range(500):
        a.step(0.1)
        b.step(0.1)
    assert (a.ex, a.ey, a.eth) == (b.ex, b.ey, b.eth)


def test_amcl_error_statistics_over_a_long_drive() -> None:
    # Two hours of driving at 10 Hz: errors like AMCL on a Turtlebot (2-5 cm, 1-3 deg).
    loc = amcl(11)
    pos, head = [], []
    for _ in range(72_000):
        loc.step(0.1)
        pos.append(math.hypot(loc.ex, loc.ey))
        head.append(abs(loc.eth))
    mean_pos = float(np.mean(pos))
    assert 0.02 <= mean_pos <= 0.06, mean_pos
    assert math.radians(1.0) <= float(np.mean(head)) <= math.radians(3.0)
    assert float(np.percentile(pos, 99)) < 0.3  # jumps are rare and fade


def test_jumps_happen_at_the_configured_rate() -> None:
    loc = amcl(21, REALISTIC.model_copy(update={"jump_rate": 0.02}))
    driven = 10_000.0
    for _ in range(round(driven / 0.1)):
        loc.step(0.1)
    expected = 0.02 * driven  # 200; Poisson sd ~14
    assert loc.jumps == pytest.approx(expected, rel=0.2)
    assert amcl(21, REALISTIC.model_copy(update={"jump_rate": 0.0})).jumps == 0


def test_a_jump_moves_the_estimate_and_fades() -> None:
    p = QUIET.model_copy(update={"jump_rate": 1.0, "jump_sigma": 0.5, "loc_time_constant": 2.0})
    loc = amcl(4, p)
    while loc.jumps == 0:
        loc.step(0.1)
    size = math.hypot(loc.ex, loc.ey)
    assert size > 0.0
    loc._jump_rate, loc._next_jump = 0.0, math.inf  # no further jumps
    for _ in range(200):  # 20 s = 10 time constants
        loc.step(0.1)
    assert math.hypot(loc.ex, loc.ey) < 1e-3 * max(size, 1.0)


def test_tie_break_weights_pick_different_equal_routes_without_touching_the_planner() -> None:
    # A pillar between start and goal: round it above or below, equally long.
    occ = blank(8.0, 8.0)
    fill(occ, 3.5, 3.5, 4.5, 4.5)
    grid = OccupancyGrid(occ, RES)
    planner = GridPlanner(grid, RobotParams())
    before = planner._weights.copy()
    start, goal = (1.0, 4.0), (7.0, 4.0)
    plain = planner.plan(start, goal)
    assert plain is not None
    routes = set()
    for seed in range(8):
        w = planner.tie_break_weights(np.random.default_rng(seed), 0.02)
        assert np.all(w[np.isfinite(before)] >= 1.0)
        assert np.array_equal(np.isinf(w), np.isinf(before))
        path = planner.plan(start, goal, weights=w)
        assert path is not None
        assert path.length == pytest.approx(plain.length, rel=0.1)  # a tie, give or take
        routes.add(max(y for _, y in path.waypoints) > 4.0)  # above the pillar?
    assert np.array_equal(planner._weights, before)  # the shared planner is never written
    assert routes == {True, False}
