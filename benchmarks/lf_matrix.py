"""The LF study of issue 4: S1 missions with LF and NB on the same seeds for every
combination of {WLAN+SLT, AH+SLT, AH+SSD} x SPL {0, 25, 50, 75} x seeds 1..N.

Prints one line per (combination, SPL, seed) and a Markdown summary: LF and NB success
counts, mean maximum separation, and the LF/NB movement-time ratio.

    .venv/bin/python benchmarks/lf_matrix.py [--seeds 5] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections import defaultdict
from pathlib import Path
from typing import Any

from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import run_mission

ROOT = Path(__file__).resolve().parents[1]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"
COMBINATIONS = [("wlan", "slt"), ("ah", "slt"), ("ah", "ssd")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    world = ScenarioResources.load(S1)
    rows: list[dict[str, Any]] = []
    for network, threshold in COMBINATIONS:
        for spl in (0, 25, 50, 75):
            for seed in range(1, args.seeds + 1):
                row: dict[str, Any] = {"network": network, "threshold": threshold, "spl": spl}
                row["seed"] = seed
                for behaviour in ("lf", "nb"):
                    config = make_config(
                        None,
                        scenario=S1,
                        network=network,
                        threshold=threshold,
                        behaviour=behaviour,
                        spl=spl,
                        seed=seed,
                    )
                    result = run_mission(config, world)
                    m = result.mission
                    row[behaviour] = {
                        "successful": m["successful"],
                        "failed_tasks": m["failed_tasks"],
                        "sim_time_s": result.sim_time_s,
                        "max_separation": m["max_separation"],
                        "movement_time": m["total_movement_time"],
                        "timed_out": m["timed_out"],
                    }
                rows.append(row)
                lf, nb = row["lf"], row["nb"]
                print(
                    f"{network.upper()}+{threshold.upper()} SPL{spl} seed {seed}: "
                    f"LF {'ok' if lf['successful'] else 'FAILED ' + str(lf['failed_tasks'])} "
                    f"in {lf['sim_time_s']:.0f} s, max separation {lf['max_separation']:.1f} m "
                    f"(NB {nb['max_separation']:.1f} m), movement {lf['movement_time']:.0f} s "
                    f"(NB {nb['movement_time']:.0f} s)",
                    flush=True,
                )
    groups: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    for row in rows:
        groups[(row["network"], row["threshold"])].append(row)
    print()
    print(
        "| combination | LF successful | NB successful | mean max separation LF / NB (m) "
        "| movement time LF / NB |"
    )
    print("|---|---|---|---|---|")
    for (network, threshold), group in groups.items():

        def mean(behaviour: str, key: str, group: list[dict[str, Any]] = group) -> float:
            return statistics.mean(r[behaviour][key] for r in group)

        print(
            f"| {network.upper()}+{threshold.upper()} "
            f"| {sum(r['lf']['successful'] for r in group)}/{len(group)} "
            f"| {sum(r['nb']['successful'] for r in group)}/{len(group)} "
            f"| {mean('lf', 'max_separation'):.1f} / {mean('nb', 'max_separation'):.1f} "
            f"| {mean('lf', 'movement_time') / mean('nb', 'movement_time'):.2f}x |"
        )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
