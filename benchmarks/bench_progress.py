"""Cost of the progress line of ``mrcomm run``: S2 · AH · NB · SPL 25, 300 s, with and
without the mission's progress callback (its per-step call and clock read; the line
is drawn by rich's own thread), interleaved, pinned to one core.

    .venv/bin/python benchmarks/bench_progress.py [--pairs 7]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import time
from pathlib import Path

from mrcomm.bundled import resolve
from mrcomm.cli.progress import MissionProgress, ProgressLine
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import run_mission


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=7)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    s2 = resolve(Path("s2"), "scenario")
    resources = ScenarioResources.load(s2)
    config = make_config(None, scenario=s2, network="ah", spl=25, seed=1, max_time=300)
    walls: dict[str, list[float]] = {"plain": [], "progress": []}
    for _ in range(args.pairs):
        for case in walls:
            line = ProgressLine("mission", 300, enabled=False)
            callback = MissionProgress(line) if case == "progress" else None
            start = time.perf_counter()
            run_mission(config, resources, None, callback)
            walls[case].append(time.perf_counter() - start)
    for case, values in walls.items():
        print(f"{case}: median {statistics.median(values):.3f} s, min {min(values):.3f}, "
              f"max {max(values):.3f}")  # fmt: skip
    usage = resource.getrusage(resource.RUSAGE_SELF)
    print(f"CPU {usage.ru_utime + usage.ru_stime:.1f} s; load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
