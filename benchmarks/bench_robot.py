"""Benchmark of the robot layer: microseconds per SimBase.update() while following a
path, milliseconds per plan across the map, and how much faster than real time three
robots drive (robot layer only: no agents, no network).

Run: ``.venv/bin/python benchmarks/bench_robot.py [path/to/map.yaml]`` (default: the
office map, or a synthetic 54 m x 23.5 m corridor map when it is missing). Every figure
is the median of several runs.
"""

from __future__ import annotations

import math
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mrcomm.robot import GridPlanner, RobotParams, SimBase
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid

RUNS = 7
DT = 0.1
OFFICE = Path(__file__).resolve().parent.parent / "data" / "maps" / "office.yaml"
# Far-apart free points of the office map (m): start/goal pairs and a team start.
OFFICE_PAIRS = [((5.0, 7.0), (49.0, 7.0)), ((4.0, 6.0), (27.0, 20.0)), ((20.0, 17.0), (45.0, 6.0))]
OFFICE_TEAM = [(26.5, 20.0), (27.2, 20.0), (27.9, 20.0)]
OFFICE_GOALS = [(5.0, 7.0), (49.0, 7.0), (27.0, 10.0)]


def synthetic_map() -> tuple[OccupancyGrid, list, list, list]:
    """54 m x 23.5 m: rooms along a 2 m corridor, 0.9 m doors (stand-in for the office)."""
    res = 0.05
    occ = np.zeros((470, 1080), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    occ[200:202, :] = True  # corridor walls at y = 10 and 12
    occ[240:242, :] = True
    for x in range(100, 1080, 100):  # room walls every 5 m
        occ[:200, x : x + 2] = True
        occ[242:, x : x + 2] = True
    for x in range(40, 1080, 100):  # one door per room on each side
        occ[200:202, x : x + 18] = False
        occ[240:242, x : x + 18] = False
    grid = OccupancyGrid(occ, res)
    pairs = [((2.5, 5.0), (52.0, 5.0)), ((2.5, 18.0), (47.0, 5.0)), ((12.0, 5.0), (37.0, 18.0))]
    team = [(26.0, 5.0), (27.0, 5.0), (28.0, 5.0)]
    goals = [(2.5, 18.0), (52.0, 18.0), (12.0, 5.0)]
    return grid, pairs, team, goals


def median_of(fn: Callable[[], float], runs: int = RUNS) -> float:
    return statistics.median(fn() for _ in range(runs))


def bench_plan(
    planner: GridPlanner, start: tuple[float, float], goal: tuple[float, float]
) -> float:
    def once() -> float:
        t = time.perf_counter()
        path = planner.plan(start, goal)
        elapsed = time.perf_counter() - t
        assert path is not None, f"no path {start} -> {goal}"
        return elapsed * 1e3

    return median_of(once)


def bench_update(
    grid: OccupancyGrid,
    planner: GridPlanner,
    start: tuple[float, float],
    goal: tuple[float, float],
    mates: str,
) -> float:
    """µs per update() call while the robot follows its path (until it arrives).

    ``mates``: "none"; "far" (two robots out of sensing range); "trailing" (two robots
    following 1 m and 1.5 m behind on our own track: in range, so every step runs the
    blocked-path check)."""

    def once() -> float:
        base = SimBase("r", grid, planner, Pose(*start), planner.params, np.random.default_rng(0))
        base.navigate_to(*goal)
        track = [start] * 30
        others: list[tuple[float, float]] = []
        if mates == "far":
            others = [(start[0] + 100.0, start[1]), (start[0] - 100.0, start[1])]
        now = 0.0
        spent = 0
        calls = 0
        clock = time.perf_counter_ns
        while base.status.value == "active" and now < 1000.0:
            if mates == "trailing":
                others = [track[-20], track[-30]]
            t = clock()
            base.update(DT, now, others)
            spent += clock() - t
            calls += 1
            now += DT
            if mates == "trailing":
                tp = base.true_pose
                track.append((tp.x, tp.y))
        assert base.status.value == "succeeded"
        return spent / calls / 1e3

    return median_of(once)


def bench_team(
    grid: OccupancyGrid,
    planner: GridPlanner,
    team: list[tuple[float, float]],
    goals: list[tuple[float, float]],
) -> tuple[float, float]:
    """(simulated s, real-time factor) of three robots driving to their goals."""

    def once() -> tuple[float, float]:
        bases = [
            SimBase(
                f"robot_{i}",
                grid,
                planner,
                Pose(x, y, -math.pi / 2),
                planner.params,
                np.random.default_rng(i),
            )
            for i, (x, y) in enumerate(team)
        ]
        t = time.perf_counter()
        for b, g in zip(bases, goals, strict=True):
            b.navigate_to(*g)
        now = 0.0
        while now < 600.0 and any(b.status.value == "active" for b in bases):
            for b in bases:
                others = [(o.true_pose.x, o.true_pose.y) for o in bases if o is not b]
                b.update(DT, now, others)
            now += DT
        return now, now / (time.perf_counter() - t)

    results = [once() for _ in range(RUNS)]
    return results[0][0], statistics.median(r[1] for r in results)


def main(argv: list[str]) -> None:
    params = RobotParams()
    map_path = Path(argv[0]) if argv else OFFICE
    if map_path.exists():
        from mrcomm.world.mapio import load_map

        grid = load_map(map_path)
        pairs, team, goals, name = OFFICE_PAIRS, OFFICE_TEAM, OFFICE_GOALS, str(map_path)
    else:
        grid, pairs, team, goals = synthetic_map()
        name = "synthetic 54 m x 23.5 m"
    print(
        f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}"
    )
    print(f"map: {name} ({grid.width}x{grid.height} cells @ {grid.resolution} m)")
    t = time.perf_counter()
    planner = GridPlanner(grid, params)
    print(f"planner build: {(time.perf_counter() - t) * 1e3:.1f} ms (incl. distance field)")
    for start, goal in pairs:
        path = planner.plan(start, goal)
        assert path is not None
        ms = bench_plan(planner, start, goal)
        print(
            f"plan {start} -> {goal}: {path.length:.1f} m, {len(path.waypoints)} waypoints, "
            f"{ms:.2f} ms (median of {RUNS})"
        )
    start, goal = pairs[0]
    for mates in ("none", "far", "trailing"):
        us = bench_update(grid, planner, start, goal, mates)
        print(f"update while following, mates {mates}: {us:.1f} µs/call (median of {RUNS})")
    sim_s, factor = bench_team(grid, planner, team, goals)
    print(f"3 robots to far goals: {sim_s:.0f} s simulated, {factor:.0f}x real time (median)")


if __name__ == "__main__":
    main(sys.argv[1:])
