"""Benchmark of ``mrcomm report``: seconds to build the whole report (every statistic,
every figure as PNG, SVG and PDF, the HTML) of the AH reference set, 360 runs, with
the figures encoded in this process and in worker processes (interleaved).

With ``--db`` it times an existing database (e.g. a real ``mrcomm sweep
data/experiments/ah.yaml``). Without it, it builds a *synthetic* 360-run database:
the AH schema is swept for real with ``--reps`` repetitions (default 2: 24 missions),
then every run is copied with a new repetition number until each configuration has 30
runs (the copies repeat the rows, so the statistics see many ties; the amount of data
the report handles is that of the real study). The median of ``--repeats`` builds is
reported, with CPU time (this process and its encoding workers).

    .venv/bin/python benchmarks/bench_report.py [--db PATH] [--repeats 3] [--jobs 2]
        [--keep DIR] [--encoders 1,2]
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import duckdb

from mrcomm.analysis.encoding import available_cpus
from mrcomm.analysis.report import build_report, load_study
from mrcomm.experiment.tables import RUN_TABLES

ROOT = Path(__file__).resolve().parents[1]
AH_SCHEMA = ROOT / "data" / "experiments" / "ah.yaml"
TARGET_REPS = 30
BUDGET_S = 60.0


def synthetic_db(directory: Path, reps: int, jobs: int) -> Path:
    """Sweep the AH set with ``reps`` repetitions, then copy runs up to 30 each."""
    db = directory / "ah-synthetic.duckdb"
    subprocess.run(
        [
            sys.executable,
            "-c",
            "from mrcomm.cli.main import app; app()",
            "sweep",
            str(AH_SCHEMA),
            "--reps",
            str(reps),
            "--jobs",
            str(jobs),
            "--db",
            str(db),
        ],
        check=True,
        cwd=ROOT,
    )
    con = duckdb.connect(str(db))
    try:
        con.execute("BEGIN")
        for rep in range(reps + 1, TARGET_REPS + 1):
            source = (rep - 1) % reps + 1  # cycle through the real repetitions
            new_id = f"config_id || '-r{rep:03d}'"
            con.execute(
                f"INSERT INTO runs SELECT * REPLACE ({new_id} AS run_id, {rep} AS repetition) "
                f"FROM runs WHERE repetition = {source}"
            )
            for table in RUN_TABLES:
                if table == "runs":
                    continue
                # Copy the child rows of the source repetition under the new run ids.
                con.execute(
                    f"INSERT INTO {table} SELECT t.* REPLACE (r.{new_id} AS run_id) "
                    f"FROM {table} t JOIN runs r ON t.run_id = r.run_id "
                    f"WHERE r.repetition = {source}"
                )
        con.execute("COMMIT")
        n = con.execute("SELECT count(*) FROM runs").fetchone()
    finally:
        con.close()
    print(
        f"synthetic database: {n[0] if n else 0} runs ({reps} real repetitions copied to "
        f"{TARGET_REPS})"
    )
    return db


def _cpu_seconds() -> float:
    """CPU time of this process and its finished children (the encoding workers)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", type=Path, help="time this database (default: synthetic)")
    parser.add_argument("--reps", type=int, default=2, help="real repetitions (synthetic DB)")
    parser.add_argument("--jobs", type=int, default=2, help="sweep workers (synthetic DB)")
    parser.add_argument(
        "--encoders",
        default=f"1,{available_cpus()}",
        help="comma-separated figure-encoding process counts to compare (interleaved)",
    )
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--keep", type=Path, help="keep the database and reports in this dir")
    args = parser.parse_args()
    cases = sorted({int(j) for j in args.encoders.split(",")})
    with tempfile.TemporaryDirectory() as scratch:
        tmp = str(args.keep or scratch)
        Path(tmp).mkdir(parents=True, exist_ok=True)
        db = args.db or synthetic_db(Path(tmp), args.reps, args.jobs)
        started = time.perf_counter()
        data = load_study(db)
        load_s = time.perf_counter() - started
        walls: dict[int, list[float]] = {j: [] for j in cases}
        cpus: dict[int, list[float]] = {j: [] for j in cases}
        figures = 0
        print(f"load before: {os.getloadavg()[0]:.2f}")
        for i in range(args.repeats):
            for jobs in cases:  # interleaved: a load change hits every case alike
                cpu, started = _cpu_seconds(), time.perf_counter()
                report = build_report(
                    load_study(db), Path(tmp) / f"report-{i}-{jobs}", db_path=db, jobs=jobs
                )
                walls[jobs].append(time.perf_counter() - started)
                cpus[jobs].append(_cpu_seconds() - cpu)
                figures = len(report.figures)
        print(f"load after: {os.getloadavg()[0]:.2f}")
        print(
            f"machine: {platform.processor() or platform.machine()}, {available_cpus()} CPUs, "
            f"Python {platform.python_version()}"
        )
        print(
            "| database | runs | figures | encoders | load s | report wall s (median) "
            "| min..max | CPU s (median) | budget |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        for jobs in cases:
            print(
                f"| {'given' if args.db else 'synthetic AH'} | {len(data.runs)} | {figures} | "
                f"{jobs} | {load_s:.2f} | **{statistics.median(walls[jobs]):.1f}** | "
                f"{min(walls[jobs]):.1f}..{max(walls[jobs]):.1f} | "
                f"{statistics.median(cpus[jobs]):.1f} | {BUDGET_S:.0f} s |"
            )
        best = min(statistics.median(w) for w in walls.values())
        if best > BUDGET_S:
            sys.exit(f"report took {best:.1f} s > {BUDGET_S:.0f} s")


if __name__ == "__main__":
    main()
