"""Generated scenarios: deterministic (same options, same bytes), every kind and start
mode loads with every start and task reachable (the loader checks), requests that
cannot fit are refused in one line with nothing written, and the bundled S2-S4 are
exactly what their documented commands make."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mrcomm import fileio
from mrcomm.errors import InputError
from mrcomm.run.resources import checked_scenario, planning_reach
from mrcomm.world.generate.make import Request, make_scenario, parse_size
from mrcomm.world.generate.maps import KINDS
from mrcomm.world.generate.place import START_MODES, START_SPACING
from mrcomm.world.occupancy import OccupancyGrid
from mrcomm.world.passages import find_passages
from mrcomm.world.scenario import load_scenario
from tests.conftest import ROOT

SMALL = {
    "office": (30, 20),
    "warehouse": (30, 24),
    "campus": (60, 50),
    "grid": (15, 12),
    "corridor": (24, 8),
}


def digest(directory: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(directory.iterdir())}


@pytest.mark.parametrize("kind", sorted(KINDS))
@pytest.mark.parametrize("start", START_MODES)
def test_every_kind_and_start_loads_with_what_was_asked(
    tmp_path: Path, kind: str, start: str
) -> None:
    width, height = SMALL[kind]
    request = Request(kind, width, height, 8, 12, start, "robot_3", 5, "gen")
    # Checked as the CLI does: every start and task reachable on the planning grid too.
    scenario = load_scenario(make_scenario(request, tmp_path / "out", checked_scenario))
    assert len(scenario.robots) == 8 and len(scenario.tasks) == 12
    # Every generated scenario's robots plan on 0.2 m cells (its passages stay open).
    assert dict(scenario.robot_settings) == {"planner_resolution": 0.2}
    assert scenario.one_lane_width == 1.3  # robots queue at doors and lanes narrower
    assert scenario.assigner.kind == "robot" and scenario.assigner.host == "robot_3"
    xs = [(r.pose.x, r.pose.y) for r in scenario.robots]
    gaps = [((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2) ** 0.5 for i, a in enumerate(xs)
            for b in xs[i + 1 :]]  # fmt: skip
    assert min(gaps) >= START_SPACING - 0.02  # (coordinates rounded to the centimetre)


def test_same_options_same_bytes_and_another_seed_differs(tmp_path: Path) -> None:
    def make(seed: int, out: str) -> dict[str, str]:
        make_scenario(Request("office", 30, 20, 6, 10, "scattered", "base", seed, "x"),
                      tmp_path / out)  # fmt: skip
        return digest(tmp_path / out)

    first = make(1, "a")
    assert make(1, "b") == first
    assert sorted(first) == ["x.yaml", "x_map.png", "x_map.yaml", "x_tasks.yaml"]
    other = make(2, "c")
    assert other["x_map.png"] != first["x_map.png"] and other["x.yaml"] != first["x.yaml"]


def test_assigner_kinds(tmp_path: Path) -> None:
    for i, (given, kind) in enumerate([("base", "base_station"), ("virtual", "virtual")]):
        request = Request("grid", 15, 12, 3, 3, "scattered", given, 1, "g")
        scenario = load_scenario(make_scenario(request, tmp_path / str(i)))
        assert scenario.assigner.kind == kind
        if kind == "base_station":
            assert scenario.assigner.position is not None


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"robots": 500}, "--robots: 500 robots do not fit on a 20x15 m office (at most ~"),
        ({"tasks": 5000}, "--tasks: 5000 tasks do not fit on a 20x15 m office"),
        ({"width": 2000, "height": 2000}, "--size: 2000x2000 m is 400,000,000 cells at 0.1 m"),
        ({"robots": 0}, "--robots: must be 1-"),
        ({"kind": "castle"}, "--map: unknown map 'castle'"),
        ({"start": "ring"}, "--start: unknown start 'ring'"),
        ({"assigner": "robot_99"}, "robot_K with K in 1..4"),
        ({"width": 5}, "needs sides of at least"),
        ({"name": "a/b"}, "not a file name stem"),
    ],
)
def test_impossible_requests_are_refused_and_nothing_is_written(
    tmp_path: Path, change: dict[str, object], message: str
) -> None:
    fields = {"kind": "office", "width": 20.0, "height": 15.0, "robots": 4, "tasks": 6,
              "start": "scattered", "assigner": "robot_1", "seed": 1, "name": "n"}  # fmt: skip
    request = Request(**{**fields, **change})  # type: ignore[arg-type]
    with pytest.raises(InputError, match=re.escape(message)):
        make_scenario(request, tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


def test_an_unwritable_output_is_refused_before_drawing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def refuse(**_: object) -> str:
        raise PermissionError(13, "Permission denied")

    def no_drawing(*_: object) -> None:
        raise AssertionError("drew a plan for an output it cannot write")

    monkeypatch.setattr(fileio.tempfile, "mkdtemp", refuse)  # the staging directory
    monkeypatch.setitem(KINDS, "grid", (no_drawing, 8.0))
    request = Request("grid", 15, 12, 2, 2, "scattered", "virtual", 1, "g")
    with pytest.raises(InputError, match="--out: cannot write there: Permission denied"):
        make_scenario(request, tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


def test_an_output_directory_with_files_is_never_overwritten(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    with pytest.raises(InputError, match="not an empty directory"):
        make_scenario(Request("grid", 15, 12, 2, 2, "scattered", "virtual", 1, "g"), out)
    assert [p.name for p in out.iterdir()] == ["keep.txt"]


@pytest.mark.parametrize("text", ["60x", "x40", "nanxnan", "infx3", "-5x4", "0x10", "3000x10"])
def test_bad_sizes(text: str) -> None:
    with pytest.raises(InputError, match="--size"):
        parse_size(text)


@pytest.mark.parametrize("name", ["s2", "s3", "s4", "campus1000"])
def test_the_bundled_scenarios_are_what_their_commands_make(tmp_path: Path, name: str) -> None:
    """Each bundled scenario's header holds the command that made it: run again as the
    command runs it (starts and tasks only where the robots' planning grid reaches), it
    makes the same bytes (campus1000 in ~4 s)."""
    bundled = ROOT / "data" / "scenarios" / name
    header = (bundled / f"{name}.yaml").read_text().splitlines()[0]
    command = header.removeprefix("# Generated by: mrcomm scenario make ").split()
    options = dict(zip(command[::2], command[1::2], strict=True))
    width, height = parse_size(options["--size"])
    request = Request(
        options["--map"], width, height, int(options["--robots"]), int(options["--tasks"]),
        options["--start"], options["--assigner"], int(options["--seed"]), options["--name"],
    )  # fmt: skip
    make_scenario(request, tmp_path / name, checked_scenario, reach=planning_reach)
    assert digest(tmp_path / name) == digest(bundled)


def test_starts_and_tasks_go_only_on_the_cells_the_robots_reach(tmp_path: Path) -> None:
    """With ``reach``, the generator passes over the cells it rules out (here the west
    half) in the same order of draws; ruling none out makes the same bytes as without."""
    request = Request("office", 40, 30, 12, 20, "scattered", "robot_1", 2, "half")

    def east(grid: Any, settings: Any, points: Any) -> Any:
        return points[:, 0] > 20.0

    path = make_scenario(request, tmp_path / "half", checked_scenario, reach=east)
    scenario = load_scenario(path)
    assert all(r.pose.x > 20.0 for r in scenario.robots)
    assert all(t.x > 20.0 for t in scenario.tasks)
    make_scenario(request, tmp_path / "none", checked_scenario)
    make_scenario(request, tmp_path / "all", checked_scenario,
                  reach=lambda g, s, p: np.ones(len(p), dtype=bool))  # fmt: skip
    renamed = {k.replace("all", "none"): v for k, v in digest(tmp_path / "all").items()}
    assert renamed == digest(tmp_path / "none")


def test_planning_reach_is_the_planning_checks_region() -> None:
    """A room walled off from the rest: its points are outside the planning grid's main
    region, as check_planning_reach judges them; points by a wall (whose own planning
    cell is blocked) count by the free cell they snap to, as the check does."""
    occupied = np.zeros((100, 200), dtype=bool)  # 20 x 10 m at 0.1 m
    occupied[[0, -1], :] = occupied[:, [0, -1]] = True
    occupied[30:33, 140:180] = occupied[67:70, 140:180] = True  # a closed room
    occupied[30:70, 140:143] = occupied[30:70, 177:180] = True
    grid = OccupancyGrid(occupied, 0.1)
    points = np.array([[3.0, 5.0], [10.0, 2.0], [16.0, 5.0], [15.5, 4.5], [13.0, 5.0],
                       [13.86, 5.0]])  # fmt: skip
    reached = planning_reach(grid, {"planner_resolution": 0.2}, points)
    assert reached.tolist() == [True, True, False, False, True, True]


def test_the_thousand_robot_campus_loads() -> None:
    scenario = load_scenario(ROOT / "data" / "scenarios" / "campus1000" / "campus1000.yaml")
    assert len(scenario.robots) == 1000 and len(scenario.tasks) == 2000


def test_large_maps_repair_routes_and_the_bundled_ones_are_as_made() -> None:
    """Maps of 200 x 200 m and more get route repair; S2-S4 search whole routes again,
    as their completion was measured with; the bundled campus has the repair line."""
    from mrcomm.world.generate.make import REPAIR_HORIZON, robot_section

    assert robot_section(199.0, 200.0) == {"planner_resolution": 0.2}
    assert robot_section(200.0, 200.0) == {"planner_resolution": 0.2, "repair_horizon": 10.0}
    bundled = Path(__file__).resolve().parents[2] / "data" / "scenarios"
    for name, repair in (("s2", False), ("s3", False), ("s4", False), ("campus1000", True)):
        settings = dict(load_scenario(bundled / name / f"{name}.yaml").robot_settings)
        assert settings.get("repair_horizon") == (REPAIR_HORIZON if repair else None), name


def test_the_corridor_map_is_two_halls_joined_by_one_lane(tmp_path: Path) -> None:
    request = Request("corridor", 24, 8, 4, 4, "scattered", "virtual", 1, "lane")
    scenario = load_scenario(make_scenario(request, tmp_path / "lane"))
    passages = find_passages(scenario.grid, scenario.one_lane_width, 2 * scenario.robot_radius)
    assert len(passages) == 1
    lane = passages.passages[0]
    assert (lane.cx, lane.cy) == pytest.approx((12.0, 4.0), abs=0.05)
    assert abs(lane.ax) == pytest.approx(1.0, abs=0.01)  # through it: east-west
    assert lane.half_length == pytest.approx(3.9, abs=0.2)  # the 7.4 m lane and its mouths
    assert lane.width == pytest.approx(1.0, abs=0.1)
