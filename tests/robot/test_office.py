"""The robot layer on the shipped office map (skipped while the map is missing)."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from mrcomm.ports import NavStatus
from mrcomm.robot import GridPlanner, RobotParams
from tests.robot.robot_maps import make_base, run

OFFICE = Path(__file__).resolve().parents[2] / "data" / "maps" / "office.yaml"
P = RobotParams()


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


def test_a_snapped_start_keeps_its_cell_free_of_a_mate_disc(
    office: tuple[object, GridPlanner],
) -> None:
    """A robot in the inflated zone (deep in the office's east dead end, S1's task 7)
    searches from the free cell it is snapped to; the disc around a mate 0.6 m away
    must leave that cell open too, or every plan around the mate fails and the robot
    cannot get past it (it used to: no path, a deadlock in the dead end)."""
    _, planner = office
    start, mate, goal = (47.32, 3.57), (46.95, 4.05), (47.5, 5.0)
    assert not planner.is_free(*start)  # in the inflated zone: snapped
    s_cell = planner.snap(*start)
    assert s_cell is not None and math.dist(planner.cell_centre(*s_cell), mate) < 0.56
    path = planner.plan(start, goal, obstacles=[mate])
    assert path is not None
    pts = np.array(path.waypoints)
    for a, b in itertools.pairwise(pts[1:]):  # past the snapped start, clear of the mate
        t = np.clip(np.dot(np.subtract(mate, a), b - a) / np.dot(b - a, b - a), 0, 1)
        assert math.dist(mate, a + t * (b - a)) > 0.35
