"""The robot layer on the shipped office map (skipped while the map is missing)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mrcomm.ports import NavStatus
from mrcomm.robot import GridPlanner, RobotParams
from tests.robot.robot_maps import make_base, run

OFFICE = Path(__file__).resolve().parents[2] / "data" / "maps" / "office.yaml"
P = RobotParams()

pytestmark = pytest.mark.skipif(not OFFICE.exists(), reason="office map not generated yet")


@pytest.fixture(scope="module")
def office() -> tuple[object, GridPlanner]:
    from mrcomm.world.mapio import load_map

    grid = load_map(OFFICE)
    return grid, GridPlanner(grid, P)


def test_long_plan_is_safe(office: tuple[object, GridPlanner]) -> None:
    _, planner = office
    path = planner.plan((5.0, 7.0), (49.0, 7.0))
    assert path is not None
    assert path.length > 40.0
    body = planner.grid.inflated(P.radius)
    pts = np.array(path.waypoints)
    assert body.line_of_sight_many(pts[:-1], pts[1:]).all()


def test_three_robots_cross_the_office(office: tuple[object, GridPlanner]) -> None:
    _, planner = office
    starts = [(26.5, 20.0), (27.2, 20.0), (27.9, 20.0)]
    goals = [(5.0, 7.0), (49.0, 7.0), (27.0, 10.0)]
    bases = [
        make_base(planner.grid, (x, y, -math.pi / 2), seed=i, planner=planner)
        for i, (x, y) in enumerate(starts)
    ]
    for b, g in zip(bases, goals, strict=True):
        b.navigate_to(*g)
    traces = run(bases, 300.0, stale=True)
    assert all(b.status is NavStatus.SUCCEEDED for b in bases)
    assert all(b.bumps == 0 for b in bases)
    for tr in traces:
        assert min(planner.clearance(x, y) for _, x, y, _, _ in tr) >= P.radius
    for i in range(3):
        for j in range(i + 1, 3):
            gaps = [math.dist(a[1:3], b[1:3]) for a, b in zip(traces[i], traces[j], strict=False)]
            assert min(gaps) >= 2 * P.radius
