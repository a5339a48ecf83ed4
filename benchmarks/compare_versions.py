"""Speed of two versions of MRComm side by side: is a restructuring free?

Runs the same S1 missions with the code of two source trees (e.g. this checkout and a
``git worktree`` of an earlier commit), alternating the trees round after round so that
background load on a shared machine falls on both alike. Each round starts a fresh
process per tree pinned to one core, loads S1 once and runs every case once per seed;
wall and CPU time are measured per mission. Prints the machine's load (``uptime``) and
a Markdown table: median real-time factor (simulated s / wall s) and median CPU time per
case and tree, and the ratio new/old.

    git worktree add /tmp/mrcomm-old <commit>
    .venv/bin/python benchmarks/compare_versions.py --old /tmp/mrcomm-old --rounds 7
        [--old-python /tmp/oldvenv/bin/python]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASES: dict[str, dict[str, object]] = {
    "S1-WLAN-SPL0-NB": {"network": "wlan", "spl": 0, "behaviour": "nb"},
    "S1-AH-SPL0-NB-SSD": {"network": "ah", "spl": 0, "behaviour": "nb", "threshold": "ssd"},
    "S1-AH-SPL50-LF-SLT": {"network": "ah", "spl": 50, "behaviour": "lf", "threshold": "slt"},
    "S1-AH-SPL50-LF-SSD": {"network": "ah", "spl": 50, "behaviour": "lf", "threshold": "ssd"},
}

# Runs inside each tree's process; it imports what either version calls things.
_PROBE = r"""
import json, os, sys, time
os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
try:
    from mrcomm.run.config import make_config
    from mrcomm.run.resources import ScenarioResources as Resources
except ImportError:
    from mrcomm.sim.config import make_config
    from mrcomm.sim.world import SimWorld as Resources
from mrcomm.sim.mission import run_mission
cases, seeds, scenario = json.loads(sys.argv[1]), json.loads(sys.argv[2]), sys.argv[3]
resources = Resources.load(scenario)
out = []
for name, options in cases.items():
    for seed in seeds:
        config = make_config(None, scenario=scenario, seed=seed, **options)
        wall, cpu = time.perf_counter(), time.process_time()
        result = run_mission(config, resources)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        out.append({"case": name, "seed": seed, "sim": result.sim_time_s, "wall": wall, "cpu": cpu})
print(json.dumps(out))
"""


def measure(
    tree: Path, seeds: list[int], python: str = sys.executable
) -> list[dict[str, float | str]]:
    env = {**os.environ, "PYTHONPATH": str(tree / "src")}
    scenario = str(ROOT / "data" / "scenarios" / "s1.yaml")
    done = subprocess.run(
        [python, "-c", _PROBE, json.dumps(CASES), json.dumps(seeds), scenario],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    rows: list[dict[str, float | str]] = json.loads(done.stdout)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", type=Path, required=True, help="source tree of the old version")
    parser.add_argument("--new", type=Path, default=ROOT, help="source tree of the new version")
    parser.add_argument(
        "--old-python",
        default=sys.executable,
        help="interpreter for the old tree (a venv with the old version installed, when the "
        "two register different variants)",
    )
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--seeds", type=int, default=2, help="missions per case and round")
    args = parser.parse_args()
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"before: {uptime}")
    runs: dict[str, list[dict[str, float | str]]] = {"old": [], "new": []}
    for k in range(args.rounds):
        seeds = [k * args.seeds + s + 1 for s in range(args.seeds)]
        order = ("old", "new") if k % 2 == 0 else ("new", "old")
        for which in order:
            if which == "old":
                runs[which] += measure(args.old, seeds, args.old_python)
            else:
                runs[which] += measure(args.new, seeds)
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"after:  {uptime}")
    print()
    print("| case | old RTF | new RTF | new/old RTF | old CPU s | new CPU s | new/old CPU |")
    print("|---|---|---|---|---|---|---|")
    for case in CASES:
        stats = {}
        for which, rows in runs.items():
            mine = [r for r in rows if r["case"] == case]
            rtf = statistics.median(float(r["sim"]) / float(r["wall"]) for r in mine)
            cpu = statistics.median(float(r["cpu"]) for r in mine)
            stats[which] = (rtf, cpu)
        (o_rtf, o_cpu), (n_rtf, n_cpu) = stats["old"], stats["new"]
        print(
            f"| {case} | {o_rtf:.0f}x | {n_rtf:.0f}x | {n_rtf / o_rtf:.3f} | "
            f"{o_cpu:.3f} | {n_cpu:.3f} | {n_cpu / o_cpu:.3f} |"
        )


if __name__ == "__main__":
    main()
