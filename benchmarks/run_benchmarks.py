"""Simulation speed benchmarks: real-time factor (simulated s / wall s) of whole missions.

Pinned to one core; the scenario is loaded once (as a sweep worker does) and each
configuration is run ``--repeats`` times; the median is reported. Prints a Markdown
table for BENCHMARKS.md.

    .venv/bin/python benchmarks/run_benchmarks.py [--repeats 5] [--only NAME]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from pathlib import Path

from mrcomm.sim.config import make_config
from mrcomm.sim.mission import run_mission
from mrcomm.sim.world import SimWorld

ROOT = Path(__file__).resolve().parents[1]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"

CASES: dict[str, dict[str, object]] = {
    "S1-WLAN-SPL0-NB": {"network": "wlan", "spl": 0, "behaviour": "nb"},
    "S1-AH-SPL0-NB": {"network": "ah", "spl": 0, "behaviour": "nb"},
    "S1-AH-SPL50-NB-SLT": {"network": "ah", "spl": 50, "behaviour": "nb", "threshold": "slt"},
    "S1-AH-SPL0-NB-SSD": {"network": "ah", "spl": 0, "behaviour": "nb", "threshold": "ssd"},
    "S1-AH-SPL50-NB-SSD": {"network": "ah", "spl": 50, "behaviour": "nb", "threshold": "ssd"},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--only", action="append", help="run only these cases")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    started = time.perf_counter()
    world = SimWorld.load(S1)
    load_s = time.perf_counter() - started
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}; pinned to 1 core; scenario load {load_s:.2f} s"
    )
    print()
    print("| case | sim s (median) | wall s (median) | real-time factor (median) | min..max |")
    print("|---|---|---|---|---|")
    for name, options in CASES.items():
        if args.only and name not in args.only:
            continue
        factors, walls, sims = [], [], []
        for seed in range(1, args.repeats + 1):
            config = make_config(None, scenario=S1, seed=seed, **options)
            result = run_mission(config, world)
            factors.append(result.sim_time_s / result.wall_time_s)
            walls.append(result.wall_time_s)
            sims.append(result.sim_time_s)
        print(
            f"| {name} | {statistics.median(sims):.1f} | {statistics.median(walls):.3f} | "
            f"**{statistics.median(factors):.0f}x** | {min(factors):.0f}..{max(factors):.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
