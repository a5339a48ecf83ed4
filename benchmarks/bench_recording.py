"""What recording costs: one S1 mission (AH · LF · SLT · SPL 25, seed 3) simulated
plainly and recorded to MCAP through the Foxglove SDK, interleaved (plain, recorded,
plain, ...) in this one process so both see the same load. Prints the median wall and
CPU time of each, the file size, and ``uptime`` before and after.

    PYTHONPATH=src .venv/bin/python benchmarks/bench_recording.py --reps 5
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from mrcomm.experiment.recording import run_and_record
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import run_mission

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "data" / "scenarios" / "s1.yaml"


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--reps", type=int, default=5)
    args = parser.parse_args()
    config = make_config(
        None, scenario=SCENARIO, network="ah", behaviour="lf", threshold="slt", spl=25, seed=3
    )
    resources = ScenarioResources.load(SCENARIO)
    times: dict[str, list[tuple[float, float]]] = {"plain": [], "recorded": []}
    print("before:", uptime())
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "run.mcap"
        for _ in range(args.reps):
            for mode in times:
                wall, cpu = time.perf_counter(), time.process_time()
                if mode == "plain":
                    result = run_mission(config, resources)
                else:
                    result = run_and_record(config, resources, path)
                times[mode].append((time.perf_counter() - wall, time.process_time() - cpu))
        size = path.stat().st_size
    print("after: ", uptime())
    print(f"mission: {result.sim_time_s:.1f} s simulated; recording {size / 1e6:.2f} MB")
    for mode, rows in times.items():
        wall = statistics.median(w for w, _ in rows)
        cpu = statistics.median(c for _, c in rows)
        print(
            f"{mode:9s} median wall {wall:.3f} s, CPU {cpu:.3f} s ({result.sim_time_s / wall:.0f}x)"
        )


if __name__ == "__main__":
    main()
