"""Benchmark of the heap setting (``mrcomm.heap.keep_freed_blocks``): what page faults of
freshly mapped memory cost a planner search and a large team's simulation.

Each case runs in a fresh child process pinned to one core, with and without the
setting, interleaved over ``--repeats`` rounds (median reported), with the page faults
the child took and its CPU time:

* ``search``: 200 searches on an open grid of 400 x 600 and of 1500 x 1500 cells (the
  S4 and campus planning grids) between neighbouring cells: what a search costs beyond
  its expansions (pyastar2d allocates a cost and a parent array over the grid);
* ``campus`` (with ``--campus``): campus1000 (1,000 robots), NB · WLAN · SPL 25,
  ``--sim-time`` s simulated (default 5).

Run: ``.venv/bin/python benchmarks/bench_heap.py [--repeats 3] [--campus]``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CAMPUS = ROOT / "data" / "scenarios" / "campus1000" / "campus1000.yaml"

PRELUDE = """
import json, resource, sys, time
from mrcomm import heap
if sys.argv[1] == "keep":
    assert heap.keep_freed_blocks()
else:
    heap._done = False  # as if not glibc: the planner leaves the heap as it is
def report(**extra):
    usage = resource.getrusage(resource.RUSAGE_SELF)
    print(json.dumps({"cpu": time.process_time() - cpu0, "faults": usage.ru_minflt - faults0,
                      **extra}))
"""

SEARCH = (
    PRELUDE
    + """
import numpy as np, pyastar2d
grids = [np.ones(shape, dtype=np.float32) for shape in ((400, 600), (1500, 1500))]
faults0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
cpu0 = time.process_time()
per = {}
for grid in grids:
    t = time.process_time()
    for _ in range(200):
        pyastar2d.astar_path(grid, (10, 10), (11, 11), allow_diagonal=True)
    per[f"{grid.shape[0]}x{grid.shape[1]}"] = (time.process_time() - t) / 200 * 1e3
report(ms_per_search=per)
"""
)

CAMPUS_RUN = (
    PRELUDE
    + """
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission
scenario, sim_time = sys.argv[2], float(sys.argv[3])
resources = ScenarioResources.load(scenario)
config = make_config(None, scenario=scenario, network="wlan", spl=25.0, behaviour="nb",
                     threshold="none", max_time=sim_time, seed=1)
mission = Mission(config, resources)
faults0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
cpu0 = time.process_time()
while mission.now < sim_time - 1e-9 and not mission.done:
    mission.step()
report(sim=mission.now, peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
"""
)


def child(code: str, mode: str, *args: str) -> dict[str, float]:
    command = [sys.executable, "-c", code, mode, *args]
    if sys.platform.startswith("linux"):
        command = ["taskset", "-c", "0", *command]
    done = subprocess.run(command, capture_output=True, text=True, check=True, cwd=ROOT)
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--campus", action="store_true")
    parser.add_argument("--sim-time", type=float, default=5.0)
    args = parser.parse_args()
    print(f"{os.cpu_count()} CPUs, pinned to one core; load {os.getloadavg()}")
    cases = {"search": (SEARCH, ())}
    if args.campus:
        cases["campus"] = (CAMPUS_RUN, (str(CAMPUS), str(args.sim_time)))
    runs: dict[tuple[str, str], list[dict[str, float]]] = {}
    for _ in range(args.repeats):
        for name, (code, extra) in cases.items():
            for mode in ("default", "keep"):  # interleaved
                runs.setdefault((name, mode), []).append(child(code, mode, *extra))
    print(f"load after: {os.getloadavg()}")
    print("| case | heap | CPU s | page faults | detail |")
    print("|---|---|---|---|---|")
    for (name, mode), results in runs.items():
        cpu = statistics.median(r["cpu"] for r in results)
        faults = statistics.median(r["faults"] for r in results)
        if name == "search":
            detail = ", ".join(
                f"{shape}: {statistics.median(r['ms_per_search'][shape] for r in results):.3f} "
                "ms per search"
                for shape in results[0]["ms_per_search"]
            )
        else:
            peak = max(r["peak_mb"] for r in results)
            detail = f"{results[0]['sim']:g} s simulated, peak {peak:.0f} MB"
        print(f"| {name} | {mode} | {cpu:.2f} | {faults:.0f} | {detail} |")


if __name__ == "__main__":
    main()
