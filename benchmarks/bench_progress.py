"""Cost of the progress line (`.venv/bin/python benchmarks/bench_progress.py`): S2 · AH · NB · SPL 25, 300 s, with and without the
MissionProgress callback (drawing disabled: what remains is the per-step call and the
clock read), interleaved, pinned to one core."""

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

os.sched_setaffinity(0, {0})
s2 = resolve(Path("s2"), "scenario")
res = ScenarioResources.load(s2)
config = make_config(None, scenario=s2, network="ah", spl=25, seed=1, max_time=300)
walls = {"plain": [], "progress": []}
for k in range(7):
    for case in ("plain", "progress"):
        line = ProgressLine("mission", 300, enabled=False)
        line.enabled = True  # the callback's own work; nothing drawn (no task)
        cb = MissionProgress(line) if case == "progress" else None
        t = time.perf_counter()
        r = run_mission(config, res, None, cb)
        walls[case].append(time.perf_counter() - t)
for case, w in walls.items():
    print(case, f"median {statistics.median(w):.3f} s, min {min(w):.3f}, max {max(w):.3f}")
ru = resource.getrusage(resource.RUSAGE_SELF)
print(f"cpu {ru.ru_utime + ru.ru_stime:.1f} s; load {os.getloadavg()}")
