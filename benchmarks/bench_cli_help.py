"""Wall and CPU time of ``mrcomm --help``, ``mrcomm --version`` and, for contrast,
``mrcomm run --help`` (which imports the simulator): fresh interpreters through the
installed console script, cases interleaved, median of N. Target: ``--help`` < 0.5 s.

    .venv/bin/python benchmarks/bench_cli_help.py --repeats 15
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

SCRIPT = Path(sys.executable).with_name("mrcomm")
CASES = {"--help": ["--help"], "--version": ["--version"], "run --help": ["run", "--help"]}


def once(args: list[str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([str(SCRIPT), *args], check=True, capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=15)
    repeats = parser.parse_args().repeats
    print(f"load before: {os.getloadavg()[0]:.2f}")
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in CASES}
    for args in CASES.values():
        once(args)  # warm the file cache
    for _ in range(repeats):
        for name, args in CASES.items():
            times[name].append(once(args))
    print(f"load after: {os.getloadavg()[0]:.2f}")
    print("| command | wall s (median) | min..max | CPU s (median) |")
    print("|---|---|---|---|")
    for name, values in times.items():
        walls = [w for w, _ in values]
        cpus = [c for _, c in values]
        print(
            f"| mrcomm {name} | {statistics.median(walls):.3f} | "
            f"{min(walls):.3f}..{max(walls):.3f} | {statistics.median(cpus):.3f} |"
        )


if __name__ == "__main__":
    main()
