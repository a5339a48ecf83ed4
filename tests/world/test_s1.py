"""The shipped office map and scenario S1 satisfy what SPEC §6 asks of them."""

from __future__ import annotations

import importlib.util
import itertools
import math
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from scipy import ndimage

from mrcomm.world.mapio import load_map
from mrcomm.world.scenario import Scenario, load_scenario

ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"
OFFICE = ROOT / "data" / "maps" / "office.yaml"
PLANNER_INFLATION = 0.2  # robot radius 0.18 m plus a margin, as the planner uses


@pytest.fixture(scope="module")
def s1() -> Scenario:
    return load_scenario(S1)


@pytest.fixture(scope="module")
def office_script() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "make_office_map", ROOT / "scripts" / "make_office_map.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["make_office_map"] = module  # dataclasses look their module up here
    try:
        spec.loader.exec_module(module)
    finally:
        del sys.modules["make_office_map"]
    return module


def test_shipped_map_is_what_the_script_draws(office_script: ModuleType) -> None:
    shipped = load_map(OFFICE)
    drawn = office_script.draw_office()
    assert shipped.resolution == drawn.resolution == 0.05
    assert shipped.origin == drawn.origin
    np.testing.assert_array_equal(shipped.occupied, drawn.occupied)


def test_office_size_and_outside_occupied() -> None:
    grid = load_map(OFFICE)
    free_iy, free_ix = np.nonzero(~grid.occupied)
    width = (free_ix.max() - free_ix.min() + 1) * grid.resolution
    height = (free_iy.max() - free_iy.min() + 1) * grid.resolution
    assert 45.0 <= width <= 60.0
    assert 20.0 <= height <= 30.0
    border = np.concatenate(
        [grid.occupied[0], grid.occupied[-1], grid.occupied[:, 0], grid.occupied[:, -1]]
    )
    assert border.all()


def test_start_room_doors_pass_one_robot_at_a_time(office_script: ModuleType) -> None:
    grid = load_map(OFFICE)
    room = next(r for r in office_script.ROOMS if r.name == "start room")
    assert len(room.doors) == 2
    wall_middle = office_script.CORRIDOR_HALF_WIDTH + office_script.WALL / 2
    for s_door in room.doors:
        x, y = office_script.point_at(s_door, wall_middle)
        # Half the opening: wide enough for one robot (radius 0.18 + inflation margin),
        # too narrow for two side by side (0.72 m + margins).
        half_opening = grid.clearance(x, y)
        assert PLANNER_INFLATION < half_opening <= 0.45


def test_s1_team_and_tasks(s1: Scenario) -> None:
    assert s1.name == "S1"
    assert s1.team == ("robot_1", "robot_2", "robot_3")
    assert s1.assigner.kind == "robot" and s1.assigner.host == "robot_2"
    assert len(s1.tasks) == 7
    assert [t.task_id for t in s1.tasks] == [str(i) for i in range(1, 8)]
    assert all(t.num_robots == 1 and not t.depends for t in s1.tasks)


def test_s1_starts_are_clustered(s1: Scenario) -> None:
    for a, b in itertools.combinations(s1.robots, 2):
        gap = math.hypot(a.pose.x - b.pose.x, a.pose.y - b.pose.y)
        assert 0.8 <= gap <= 1.0, (a.id, b.id, gap)


def test_s1_tasks_are_spread_far_apart(s1: Scenario) -> None:
    dists = [math.hypot(a.x - b.x, a.y - b.y) for a, b in itertools.combinations(s1.tasks, 2)]
    assert max(dists) >= 20.0
    assert sum(d > 8.0 for d in dists) >= 10  # the 8 m ad-hoc range matters


def test_s1_clearance_and_reachability(s1: Scenario) -> None:
    grid = s1.grid
    points = [(r.pose.x, r.pose.y) for r in s1.robots] + [(t.x, t.y) for t in s1.tasks]
    for x, y in points:
        assert grid.clearance(x, y) >= 0.3, (x, y)
    labels, _ = ndimage.label(~grid.inflated(PLANNER_INFLATION).occupied)
    regions = {int(labels[grid.world_to_cell(x, y)]) for x, y in points}
    assert len(regions) == 1 and 0 not in regions
