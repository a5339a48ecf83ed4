"""Two source trees at once, one on each core, the cores swapped every round: the ratio
of their CPU times for one scenario.

On a shared VM whose speed drifts by 10-30 % within minutes, runs one after the other
(``bench_scale.py --old``) can lose a 5 % difference in the drift. Two runs at the same
moment meet the same drift, and swapping cores each round cancels a difference
between the cores. Needs two cores (Linux, ``taskset``).

Each child is :data:`bench_scale.CHILD` (NB · WLAN · SPL 25 · seed 1, the simulated
time given) with ``PYTHONPATH`` set to the tree's ``src``.

Run: ``.venv/bin/python benchmarks/bench_pair.py /tmp/mrcomm-old . --scenario campus1000
--sim-time 20 --rounds 4``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scale import CHILD, ROOT, SCENARIOS


def start(tree: Path, scenario: Path, sim_time: float, core: int) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONPATH=str(tree.resolve() / "src"))
    command = ["taskset", "-c", str(core), sys.executable, "-c", CHILD, str(scenario)]
    return subprocess.Popen(
        [*command, str(sim_time)], stdout=subprocess.PIPE, text=True, cwd=ROOT, env=env
    )


def cpu_of(child: subprocess.Popen[str]) -> float:
    out, _ = child.communicate()
    if child.returncode != 0:
        raise SystemExit(f"a child failed (exit {child.returncode})")
    return float(json.loads(out.strip().splitlines()[-1])["cpu"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("first", type=Path, help="a source tree (e.g. a git worktree)")
    parser.add_argument("second", type=Path, help="another source tree")
    parser.add_argument("--scenario", choices=sorted(SCENARIOS), default="s4")
    parser.add_argument("--sim-time", type=float, default=60.0)
    parser.add_argument("--rounds", type=int, default=4)
    args = parser.parse_args()
    if (os.cpu_count() or 1) < 2:
        raise SystemExit("needs two cores")
    scenario = SCENARIOS[args.scenario][1]
    print(f"{args.scenario}, {args.sim_time:g} s simulated; load {os.getloadavg()}")
    rounds: list[tuple[float, float]] = []
    for k in range(args.rounds):
        cores = (0, 1) if k % 2 == 0 else (1, 0)
        a = start(args.first, scenario, args.sim_time, cores[0])
        b = start(args.second, scenario, args.sim_time, cores[1])
        rounds.append((cpu_of(a), cpu_of(b)))
        print(f"round {k + 1}: CPU s {rounds[-1][0]:.2f} / {rounds[-1][1]:.2f}", flush=True)
    ratio = statistics.median(b / a for a, b in rounds)
    first = statistics.median(a for a, _ in rounds)
    second = statistics.median(b for _, b in rounds)
    print(f"median CPU s {first:.2f} / {second:.2f}; second / first, median of rounds {ratio:.3f}")
    print(f"load after {os.getloadavg()}")


if __name__ == "__main__":
    main()
