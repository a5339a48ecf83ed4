"""Sweep benchmark: wall time of a whole reference set through ``mrcomm sweep``.

Default: the AH set (16 configurations x 30 repetitions = 480 missions) with
``--jobs 2`` into a fresh temporary database; target <= 10 minutes. The command is run
as a user runs it (a subprocess, start-up and database writes included); the figures
come from the database it filled. Prints a Markdown row for BENCHMARKS.md.

    .venv/bin/python benchmarks/bench_sweep.py                      # the full AH set
    .venv/bin/python benchmarks/bench_sweep.py --reps 2             # a subset: 32 runs
    .venv/bin/python benchmarks/bench_sweep.py --schema data/experiments/wlan.yaml
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import duckdb

ROOT = Path(__file__).resolve().parents[1]
AH = ROOT / "data" / "experiments" / "ah.yaml"
TARGET_S = 600.0  # the AH set with --jobs 2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--schema", type=Path, default=AH)
    parser.add_argument("--reps", type=int, default=None, help="default: the schema's")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-sweep-") as tmp:
        db = Path(tmp) / "results.duckdb"
        command = [
            sys.executable,
            "-c",
            "from mrcomm.cli.main import app; app()",
            "sweep",
            str(args.schema),
            "--jobs",
            str(args.jobs),
            "--db",
            str(db),
        ]
        if args.reps is not None:
            command += ["--reps", str(args.reps)]
        started = time.perf_counter()
        proc = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
        wall = time.perf_counter() - started
        if proc.returncode not in (0, 1):  # 1: some runs failed, still a measurement
            sys.exit(f"sweep failed ({proc.returncode}): {proc.stderr.strip()}")
        con = duckdb.connect(str(db), read_only=True)
        rows = con.execute("SELECT status, wall_time_s, sim_time_s FROM runs").fetchall()
        sizes = {
            t: con.execute(f"SELECT count(*) FROM {t}").fetchone()[0]  # type: ignore[index]
            for t in ("robot_metrics", "intervals", "events", "rssi")
        }
        con.close()
        db_mb = db.stat().st_size / 1e6
    n = len(rows)
    ok = sum(1 for s, _, _ in rows if s == "ok")
    run_walls = [w for _, w, _ in rows if w is not None]
    sims = [s for _, _, s in rows if s is not None]
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}; schema {args.schema.name}, --jobs {args.jobs}"
    )
    print(f"stored rows: {sizes}; database {db_mb:.1f} MB")
    print()
    print(
        "| set | runs (ok) | sweep wall s | per run wall s (median) | sim s (median) "
        "| runs/min | parallel efficiency | 480-run projection |"
    )
    print("|---|---|---|---|---|---|---|---|")
    per_run = statistics.median(run_walls) if run_walls else float("nan")
    efficiency = sum(run_walls) / (wall * args.jobs) if wall > 0 else float("nan")
    projection = wall / max(n, 1) * 480
    verdict = "meets" if projection <= TARGET_S else "misses"
    print(
        f"| {args.schema.stem} | {n} ({ok}) | {wall:.1f} | {per_run:.2f} | "
        f"{statistics.median(sims) if sims else float('nan'):.1f} | {n / wall * 60:.0f} | "
        f"{efficiency:.0%} | {projection / 60:.1f} min ({verdict} the 10 min target) |"
    )


if __name__ == "__main__":
    main()
