"""Do missions with large teams complete? The completion matrix for teams of 10 to 100.

For each case it simulates the bundled generated scenario to its end (or the 1800 s
time limit) and reports, per condition, how many runs hit the time limit, how many were
successful (every task's status reached the assigner), the tasks completed and the
statuses lost, and the simulated mission time:

* ``s2``: S2 (10 robots) · every behaviour (or ``--behaviour``, repeatable) · AH + SLT ·
  SPL 0 / 25 / 50 · seeds 1-10 (``--seeds``);
* ``s3``: S3 (30 robots) · every behaviour · AH + SLT · SPL 25 · seeds 1-6
  (``--s3-seeds``);
* ``s4``: S4 (100 robots) · NB · WLAN · SPL 0 · seed 1, and LF and NB · AH + SLT · SPL
  25 · seed 1 (on WLAN every robot is always connected, so LF never leaves NB's states).

Runs go to a process pool (``--workers``, default 2); each is deterministic, so the
figures do not depend on the machine, only its wall times do.

Run: ``.venv/bin/python benchmarks/bench_completion.py [--only s2 --only s3 --only s4]
[--behaviour serried ...] [--seeds 10] [--s3-seeds 6] [--workers 2]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "data" / "scenarios"
MAX_TIME = 1800.0


def cases(
    only: list[str], behaviours: list[str], seeds: int, s3_seeds: int
) -> Iterator[dict[str, Any]]:
    if "s2" in only:
        for behaviour in behaviours:
            for spl in (0, 25, 50):
                for seed in range(1, seeds + 1):
                    yield dict(scenario="s2", behaviour=behaviour, network="ah",
                               threshold="slt", spl=spl, seed=seed)  # fmt: skip
    if "s3" in only:
        for behaviour in behaviours:
            for seed in range(1, s3_seeds + 1):
                yield dict(scenario="s3", behaviour=behaviour, network="ah",
                           threshold="slt", spl=25, seed=seed)  # fmt: skip
    if "s4" in only:
        yield dict(scenario="s4", behaviour="nb", network="wlan", threshold="none", spl=0, seed=1)
        # LF where it matters, out of range (10 minutes on this machine): groups at 100.
        for behaviour in ("lf", "nb"):
            yield dict(scenario="s4", behaviour=behaviour, network="ah", threshold="slt",
                       spl=25, seed=1)  # fmt: skip


def run_case(case: dict[str, Any]) -> dict[str, Any]:
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import run_mission

    options = {k: v for k, v in case.items() if k != "scenario"}
    path = SCENARIOS / case["scenario"] / f"{case['scenario']}.yaml"
    start = time.perf_counter()
    result = run_mission(make_config(None, scenario=path, max_time=MAX_TIME, **options))
    mission = result.summary()["mission"]
    return {
        **case,
        "timed_out": mission["timed_out"],
        "successful": mission["successful"],
        "completed": mission["tasks_completed"],
        "total": mission["tasks_total"],
        "lost": len(mission["failed_tasks"]),
        "end": mission["end_time"],
        "wall": time.perf_counter() - start,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", action="append", choices=["s2", "s3", "s4"])
    parser.add_argument("--behaviour", action="append", help="S2 and S3: these (every one)")
    parser.add_argument("--seeds", type=int, default=10, help="S2 seeds 1..N")
    parser.add_argument("--s3-seeds", type=int, default=6, help="S3 seeds 1..N")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    from mrcomm.agents.behaviours import behaviour_names

    behaviours = args.behaviour or behaviour_names()
    todo = list(cases(args.only or ["s2", "s3", "s4"], behaviours, args.seeds, args.s3_seeds))
    print(f"{len(todo)} runs on {args.workers} workers; load {os.getloadavg()}")
    start = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(run_case, todo))
    print(f"{time.perf_counter() - start:.0f} s wall; load {os.getloadavg()}")
    print("| scenario | behaviour | network | SPL | runs | hit the time limit | successful "
          "| tasks completed | statuses lost | mission s (median) | slowest s |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for r in results:
        groups.setdefault((r["scenario"], r["behaviour"], r["network"], r["spl"]), []).append(r)
    for (scenario, behaviour, network, spl), runs in groups.items():
        completed = "/".join(str(r["completed"]) for r in runs)
        lost = "/".join(str(r["lost"]) for r in runs)
        print(
            f"| {scenario} | {behaviour} | {network} | {spl} | {len(runs)} "
            f"| {sum(r['timed_out'] for r in runs)} | {sum(r['successful'] for r in runs)} "
            f"| {completed} of {runs[0]['total']} | {lost} "
            f"| {statistics.median(r['end'] for r in runs):.0f} "
            f"| {max(r['end'] for r in runs):.0f} |"
        )


if __name__ == "__main__":
    main()
