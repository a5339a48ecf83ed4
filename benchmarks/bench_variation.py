"""Run-to-run variation of the simulated robots: the execution phase time of S1 · WLAN
· NB over many seeds with ``robot.variation=none`` and ``realistic``, interleaved (seed
by seed, one profile after the other) in this one process, so both see the same load.
Prints mean / standard deviation / min / max per profile, ``uptime`` before and after,
and the CPU time of the process. ``--mechanisms`` adds one row per mechanism of the
realistic profile acting alone (the others set to zero), to show where the spread
comes from.

    PYTHONPATH=src .venv/bin/python benchmarks/bench_variation.py --seeds 30 --mechanisms
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import time
from pathlib import Path
from typing import Any

from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "data" / "scenarios" / "s1.yaml"
PROFILES: dict[str, dict[str, Any]] = {
    "none": {"variation": "none"},
    "realistic": {"variation": "realistic"},
}
#: Each mechanism's parameters: zeroed to leave it out of a one-mechanism row.
MECHANISMS: dict[str, dict[str, Any]] = {
    "localisation": {
        "loc_position_sigma": 0.0,
        "loc_heading_sigma": 0.0,
        "heading_drift_sigma": 0.0,
        "jump_rate": 0.0,
    },
    "speed": {"speed_sigma": 0.0},
    "start delay": {"start_delay_max": 0.0},
    "tie-breaks": {"planner_tie_noise": 0.0},
}


def only(mechanism: str) -> dict[str, Any]:
    """The realistic profile with every other mechanism switched off."""
    off: dict[str, Any] = {"variation": "realistic"}
    for name, zeroed in MECHANISMS.items():
        if name != mechanism:
            off.update(zeroed)
    return off


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def execution_phase_time(resources: ScenarioResources, seed: int, robot: dict[str, Any]) -> float:
    """One simulated S1 · WLAN · NB run's execution phase time (simulated s)."""
    config = make_config(
        None,
        scenario=SCENARIO,
        network="wlan",
        behaviour="nb",
        seed=seed,
        params={"robot": robot},
    )
    value = Mission(config, resources).run().mission["execution_phase_time"]
    if value is None:
        raise RuntimeError(f"seed {seed}, robot {robot}: no execution phase")
    return float(value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=30, help="seeds 1..N (default 30)")
    parser.add_argument(
        "--mechanisms", action="store_true", help="also each mechanism of realistic alone"
    )
    args = parser.parse_args()
    seeds = range(1, args.seeds + 1)
    cases = dict(PROFILES)
    if args.mechanisms:
        cases.update({f"realistic, {m} only": only(m) for m in MECHANISMS})
    print(f"before: {uptime()}")
    resources = ScenarioResources.load(SCENARIO)  # shared, as a sweep's worker shares it
    times: dict[str, list[float]] = {p: [] for p in cases}
    cpu0, wall0 = time.process_time(), time.perf_counter()
    for seed in seeds:
        for name, robot in cases.items():
            times[name].append(execution_phase_time(resources, seed, robot))
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    print(f"after:  {uptime()}")
    print(f"{len(seeds)} seeds x {len(cases)} cases: CPU {cpu:.1f} s, wall {wall:.1f} s")
    print("| robot.variation | mean s | sd s | min s | max s |")
    print("|---|---|---|---|---|")
    for profile, values in times.items():
        print(
            f"| {profile} | {statistics.mean(values):.1f} | {statistics.stdev(values):.2f} "
            f"| {min(values):.1f} | {max(values):.1f} |"
        )


if __name__ == "__main__":
    main()
