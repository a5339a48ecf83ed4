"""How long one short plan takes on the largest bundled map (the 300 x 300 m campus at
10 cm, 3000 x 3000 cells): a 5 m plan in the open and the same around a mate standing
half way, median of 7. Run: ``.venv/bin/python benchmarks/bench_replan.py``."""

from __future__ import annotations

import math
import statistics
import time
from pathlib import Path

from mrcomm.robot.params import RobotParams
from mrcomm.robot.planner import GridPlanner
from mrcomm.world.scenario import load_scenario

CAMPUS = Path(__file__).resolve().parent.parent / "data/scenarios/campus1000/campus1000.yaml"


def main() -> None:
    scenario = load_scenario(CAMPUS)
    planner = GridPlanner(scenario.grid, RobotParams())
    pose = scenario.robots[0].pose
    start = (pose.x, pose.y)
    goals = (
        (start[0] + 5 * math.cos(a), start[1] + 5 * math.sin(a))
        for a in (2 * math.pi * k / 64 for k in range(64))
    )
    goal = next(g for g in goals if planner.is_free(*g))
    mate = ((start[0] + goal[0]) / 2, (start[1] + goal[1]) / 2)
    for label, mates in (("a 5 m plan", ()), ("the same around a mate", (mate,))):
        times = []
        for _ in range(7):
            t0 = time.perf_counter()
            path = planner.plan(start, goal, obstacles=mates)
            times.append(time.perf_counter() - t0)
        found = "found" if path is not None else "no path"
        print(f"{label}: {statistics.median(times) * 1000:.1f} ms ({found}, {planner.shape})")


if __name__ == "__main__":
    main()
