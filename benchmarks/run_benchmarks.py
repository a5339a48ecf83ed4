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

from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import run_mission

ROOT = Path(__file__).resolve().parents[1]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"

CASES: dict[str, dict[str, object]] = {
    "S1-WLAN-SPL0-NB": {"network": "wlan", "spl": 0, "behaviour": "nb"},
    "S1-AH-SPL0-NB": {"network": "ah", "spl": 0, "behaviour": "nb"},
    "S1-AH-SPL50-NB-SLT": {"network": "ah", "spl": 50, "behaviour": "nb", "threshold": "slt"},
    "S1-AH-SPL0-NB-SSD": {"network": "ah", "spl": 0, "behaviour": "nb", "threshold": "ssd"},
    "S1-AH-SPL50-NB-SSD": {"network": "ah", "spl": 50, "behaviour": "nb", "threshold": "ssd"},
    "S1-AH-SPL50-LF-SLT": {"network": "ah", "spl": 50, "behaviour": "lf", "threshold": "slt"},
    "S1-AH-SPL50-LF-SSD": {"network": "ah", "spl": 50, "behaviour": "lf", "threshold": "ssd"},
    "S1-RADIO-SPL50-LF-SLT": {"network": "radio", "spl": 50, "behaviour": "lf", "threshold": "slt"},
    "S1-RADIO-SPL50-LF-SSD": {"network": "radio", "spl": 50, "behaviour": "lf", "threshold": "ssd"},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--only", action="append", help="run only these cases")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    started = time.perf_counter()
    world = ScenarioResources.load(S1)
    load_s = time.perf_counter() - started
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}; pinned to 1 core; scenario load {load_s:.2f} s"
    )
    print()
    print("| case | sim s (median) | wall s (median) | real-time factor (median) | min..max |")
    print("|---|---|---|---|---|")
    cases = {n: o for n, o in CASES.items() if not args.only or n in args.only}
    factors: dict[str, list[float]] = {n: [] for n in cases}
    walls: dict[str, list[float]] = {n: [] for n in cases}
    sims: dict[str, list[float]] = {n: [] for n in cases}
    # Interleaved: repeat k runs every case once (seed k), so background load falls on
    # all cases alike and their ratios stay meaningful.
    for seed in range(1, args.repeats + 1):
        for name, options in cases.items():
            config = make_config(None, scenario=S1, seed=seed, **options)  # type: ignore[arg-type]
            result = run_mission(config, world)
            factors[name].append(result.sim_time_s / result.wall_time_s)
            walls[name].append(result.wall_time_s)
            sims[name].append(result.sim_time_s)
    for name in cases:
        print(
            f"| {name} | {statistics.median(sims[name]):.1f} | "
            f"{statistics.median(walls[name]):.3f} | **{statistics.median(factors[name]):.0f}x** | "
            f"{min(factors[name]):.0f}..{max(factors[name]):.0f} |",
            flush=True,
        )
    if "S1-AH-SPL0-NB" in cases and "S1-AH-SPL0-NB-SSD" in cases:
        base = statistics.median(factors["S1-AH-SPL0-NB"])
        ssd = statistics.median(factors["S1-AH-SPL0-NB-SSD"])
        # Paired by seed (the two runs of a repeat are back to back, same mission): the
        # ratio of a pair is robust to the machine's load drifting between repeats.
        paired = [
            100 * (1 - s / b)
            for b, s in zip(factors["S1-AH-SPL0-NB"], factors["S1-AH-SPL0-NB-SSD"], strict=True)
        ]
        print(
            f"\nSSD costs {100 * (1 - ssd / base):.1f} % of the no-threshold real-time factor "
            f"(ratio of medians); paired by seed: median {statistics.median(paired):.1f} %, "
            f"range {min(paired):.1f}..{max(paired):.1f} %"
        )
    base_lf, radio_lf = "S1-AH-SPL50-LF-SLT", "S1-RADIO-SPL50-LF-SSD"
    if base_lf in cases and radio_lf in cases:
        base = statistics.median(factors[base_lf])
        radio = statistics.median(factors[radio_lf])
        paired = [
            100 * (1 - r / b) for b, r in zip(factors[base_lf], factors[radio_lf], strict=True)
        ]
        print(
            f"\nThe radio with SSD costs {100 * (1 - radio / base):.1f} % of AH LF SLT's "
            f"real-time factor (ratio of medians; target within 35 %); paired by seed: median "
            f"{statistics.median(paired):.1f} %, range {min(paired):.1f}..{max(paired):.1f} %"
        )


if __name__ == "__main__":
    main()
