"""Do robots get through a one-lane corridor both ways? Queueing at one-lane passages
against none.

Each case is two 8 x 8 m halls joined by a 1 m lane ``L`` m long, with ``n`` robots
in each hall and each robot's two tasks in the other hall, simulated to its end or the
time limit twice: with ``one_lane_width: 1.3`` (robots queue at the lane's ends) and
without (no passages: robots meet in the lane, as before queueing). Lanes of 4 and 8 m,
2, 3, 4 and 6 robots a side, NB and LF (AH · SLT · SPL 25), seeds 1-3. The scenarios
are written under a temporary directory (starts in rows of four, tasks uniformly over
the other hall, seeded; the assigner virtual).

Run: ``.venv/bin/python benchmarks/bench_passages.py [--workers 2] [--max-time 1800]``
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import yaml

RES = 0.05


def write_case(directory: Path, lane: float, per_side: int, one_lane_width: float) -> Path:
    """Two 8 x 8 m halls joined by a 1 m wide lane ``lane`` m long; ``per_side`` robots
    in rows at the far end of each hall, two tasks each in the other hall (seeded)."""
    from mrcomm.world.mapio import save_map
    from mrcomm.world.occupancy import OccupancyGrid

    width, height = 8 + lane + 8 + 0.6, 8.6
    occupied = np.ones((int(height / RES), int(width / RES)), dtype=bool)

    def free(x0: float, x1: float, y0: float, y1: float) -> None:
        occupied[int(y0 / RES) : int(y1 / RES), int(x0 / RES) : int(x1 / RES)] = False

    free(0.3, 8.3, 0.3, 8.3)  # west hall
    free(8.3 + lane, 16.3 + lane, 0.3, 8.3)  # east hall
    free(8.2, 8.4 + lane, 3.8, 4.8)  # the lane
    directory.mkdir(parents=True)
    save_map(OccupancyGrid(occupied, RES), directory / "map.yaml")
    robots: list[dict[str, Any]] = []
    for x0 in (1.5, 8.3 + lane + 1.5):
        for i in range(per_side):
            pose = {"x": x0 + 1.2 * (i % 4), "y": 1.5 + 1.5 * (i // 4), "theta": 0.0}
            robots.append({"id": f"robot_{len(robots) + 1}", "pose": pose})
    rng = np.random.default_rng(1)
    tasks = []
    for i in range(4 * per_side):  # the round robin gives task i to robot (i mod 2n) + 1
        x0 = 8.3 + lane + 1.5 if i % (2 * per_side) < per_side else 1.5
        location = {"x": round(float(x0 + rng.uniform(0, 5)), 2),
                    "y": round(float(rng.uniform(1.0, 7.5)), 2)}  # fmt: skip
        task = {"task_id": str(i + 1), "type": "SENSOR_SWEEP", "location": location}
        tasks.append({**task, "arrival_time": 0, "num_robots": 1, "duration": 0, "depends": []})
    (directory / "tasks.yaml").write_text(yaml.safe_dump(tasks, sort_keys=False))
    scenario: dict[str, Any] = {
        "name": "corridor",
        "map": "map.yaml",
        "tasks": "tasks.yaml",
        "robots": robots,
        "assigner": {"kind": "virtual"},
        "robot": {"planner_resolution": 0.1},
    }
    if one_lane_width > 0:
        scenario["one_lane_width"] = one_lane_width
    path = directory / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario, sort_keys=False))
    return path


def run_case(case: dict[str, Any]) -> dict[str, Any]:
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import run_mission

    config = make_config(
        None, scenario=case["path"], behaviour=case["behaviour"], network="ah",
        threshold="slt", spl=25, seed=case["seed"], max_time=case["max_time"],
    )  # fmt: skip
    summary = run_mission(config).summary()
    mission = summary["mission"]
    return {
        **case,
        "done": mission["tasks_completed"],
        "total": mission["tasks_total"],
        "end": mission["end_time"],
        "limit": mission["timed_out"],
        "queued": sum(r["queued"] for r in summary["robots"].values()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--max-time", type=float, default=1800.0)
    args = parser.parse_args()
    started = time.perf_counter()
    cases = []
    with tempfile.TemporaryDirectory(prefix="mrcomm-lanes-") as tmp:
        for lane in (4.0, 8.0):
            for per_side in (2, 3, 4, 6):
                for queue in (True, False):
                    where = Path(tmp) / f"{lane:g}-{per_side}-{queue}"
                    path = write_case(where, lane, per_side, 1.3 if queue else 0.0)
                    for behaviour in ("nb", "lf"):
                        for seed in (1, 2, 3):
                            cases.append(dict(path=str(path), lane=lane, per_side=per_side,
                                              queue=queue, behaviour=behaviour, seed=seed,
                                              max_time=args.max_time))  # fmt: skip
        with ProcessPoolExecutor(args.workers) as pool:
            results = list(pool.map(run_case, cases))
    print("| lane | robots a side | behaviour | queueing | complete | at the limit | "
          "mission s (median) | waits (median) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for lane in (4.0, 8.0):
        for per_side in (2, 3, 4, 6):
            for behaviour in ("nb", "lf"):
                for queue in (True, False):
                    rows = [r for r in results if (r["lane"], r["per_side"], r["behaviour"],
                            r["queue"]) == (lane, per_side, behaviour, queue)]  # fmt: skip
                    complete = sum(r["done"] == r["total"] for r in rows)
                    limit = sum(r["limit"] for r in rows)
                    end = statistics.median(r["end"] for r in rows)
                    waits = statistics.median(r["queued"] for r in rows)
                    print(f"| {lane:g} m | {per_side} | {behaviour.upper()} | "
                          f"{'yes' if queue else 'no'} | {complete} of {len(rows)} | {limit} | "
                          f"{end:,.0f} | {waits:g} |")  # fmt: skip
    for queue in (True, False):
        for behaviour in ("nb", "lf"):
            rows = [r for r in results if r["queue"] == queue and r["behaviour"] == behaviour]
            complete = sum(r["done"] == r["total"] for r in rows)
            print(
                f"{behaviour.upper()}, queueing {'on ' if queue else 'off'}: "
                f"{complete} of {len(rows)} runs complete"
            )
    print(f"{len(results)} runs in {time.perf_counter() - started:.0f} s wall")


if __name__ == "__main__":
    main()
