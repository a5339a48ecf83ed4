"""Benchmark of team size: how fast the simulation runs with 3 to 1000 robots.

For each bundled scenario (S1: 3 robots, S2: 10, S3: 30, S4: 100, campus1000: 1000) it
simulates NB · WLAN · SPL 25 for a fixed mission time (``--sim-time``, default 120 s:
long enough that every robot plans and drives, short enough for 1000 robots; with
``--whole``, each mission to its end: its first minutes, when every robot plans its
first routes, cost the most per simulated second) in a fresh
child process pinned to one core, and reports the real-time factor (simulated s per
wall s), CPU time, the cost per step, the peak resident memory of the child, and the
fitted exponent of cost per step against N (log-log least squares). Cases are run
interleaved over ``--repeats`` rounds (the median is reported), and the machine's load
is printed with them.

With ``--old DIR`` (a ``git worktree`` of an earlier commit) every case also runs on
that tree's code and its own bundled scenario file (this tree's when it has none),
interleaved with this one's, and the table gets both and their ratio.

Run: ``.venv/bin/python benchmarks/bench_scale.py [--repeats 3] [--sim-time 120 | --whole]
[--only s2 --only s3] [--figure docs/figures/scale.png] [--old /tmp/mrcomm-old]``
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = {
    "s1": (3, ROOT / "data" / "scenarios" / "s1.yaml"),
    "s2": (10, ROOT / "data" / "scenarios" / "s2" / "s2.yaml"),
    "s3": (30, ROOT / "data" / "scenarios" / "s3" / "s3.yaml"),
    "s4": (100, ROOT / "data" / "scenarios" / "s4" / "s4.yaml"),
    "campus1000": (1000, ROOT / "data" / "scenarios" / "campus1000" / "campus1000.yaml"),
}

#: Runs in the child: load (not timed), simulate, report wall, CPU, peak RSS as JSON.
CHILD = """
import json, resource, sys, time
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission
scenario, sim_time = sys.argv[1], float(sys.argv[2])
resources = ScenarioResources.load(scenario)
# sim_time 0: the whole mission, to its end or the scenario's time limit.
limit = {"max_time": sim_time} if sim_time > 0 else {}
# The case: NB · WLAN · SPL 25 · seed 1 unless options (JSON, make_config's) say otherwise.
options = {"network": "wlan", "spl": 25.0, "behaviour": "nb", "threshold": "none", "seed": 1}
options.update(json.loads(sys.argv[3]) if len(sys.argv) > 3 else {})
config = make_config(None, scenario=scenario, **options, **limit)
mission = Mission(config, resources)
wall0, cpu0 = time.perf_counter(), time.process_time()
steps = 0
while (sim_time <= 0 or mission.now < sim_time - 1e-9) and not mission.done:
    mission.step()
    steps += 1
wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"sim": mission.now, "wall": wall, "cpu": cpu, "steps": steps,
                  "peak_mb": peak}))
"""


def start_case(
    path: Path,
    sim_time: float,
    tree: Path | None = None,
    core: int = 0,
    options: dict[str, object] | None = None,
) -> subprocess.Popen[str]:
    """One case in a fresh process pinned to ``core`` (Linux); ``tree``: run that
    source tree's code instead; ``options``: make_config's, over NB · WLAN · SPL 25."""
    command = [sys.executable, "-c", CHILD, str(path), str(sim_time), json.dumps(options or {})]
    if sys.platform.startswith("linux"):
        command = ["taskset", "-c", str(core), *command]
    env = dict(os.environ)
    if tree is not None:  # its code, and its own example plugin (see same_results.py)
        tree = tree.resolve()
        env["PYTHONPATH"] = os.pathsep.join(
            str(p) for p in (tree / "src", tree / "examples" / "mrcomm-repeat")
        )
    return subprocess.Popen(command, stdout=subprocess.PIPE, text=True, cwd=ROOT, env=env)


def result_of(child: subprocess.Popen[str]) -> dict[str, float]:
    """What a case started by :func:`start_case` reported (wall, cpu, steps, peak_mb)."""
    out, _ = child.communicate()
    if child.returncode != 0:
        raise SystemExit(f"a benchmark child failed (exit {child.returncode})")
    return dict(json.loads(out.strip().splitlines()[-1]))


def run_case(path: Path, sim_time: float, tree: Path | None = None) -> dict[str, float]:
    """One case in a fresh process on core 0, waited for."""
    return result_of(start_case(path, sim_time, tree))


def fit_exponent(points: list[tuple[int, float]]) -> float:
    """Slope of log(cost per step) against log(N)."""
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(c) for _, c in points]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum(
        (x - mx) ** 2 for x in xs
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sim-time", type=float, default=120.0)
    parser.add_argument("--only", action="append", choices=sorted(SCENARIOS))
    parser.add_argument("--whole", action="store_true", help="each mission to its end")
    parser.add_argument("--figure", type=Path)
    parser.add_argument("--old", type=Path, help="an earlier tree to run side by side")
    args = parser.parse_args()
    names = args.only or list(SCENARIOS)
    if args.whole:
        args.sim_time = 0.0
    span = "whole missions" if args.whole else f"{args.sim_time:g} s simulated"
    print(f"Python {platform.python_version()}, {os.cpu_count()} CPUs, pinned to one core; "
          f"NB · WLAN · SPL 25, {span}; load {os.getloadavg()}")  # fmt: skip
    results: dict[str, list[dict[str, float]]] = {name: [] for name in names}
    before: dict[str, list[dict[str, float]]] = {name: [] for name in names}
    for _ in range(args.repeats):
        for name in names:  # interleaved: background load falls on every case alike
            results[name].append(run_case(SCENARIOS[name][1], args.sim_time))
            if args.old is not None:
                own = args.old / SCENARIOS[name][1].relative_to(ROOT)
                path = own if own.exists() else SCENARIOS[name][1]
                before[name].append(run_case(path, args.sim_time, args.old))
    print(f"load after: {os.getloadavg()}")
    if args.old is not None:
        print(f"| scenario | robots | CPU s, {args.old} | CPU s, this tree | this / old |")
        print("|---|---|---|---|---|")
        for name in names:
            old_cpu = statistics.median(r["cpu"] for r in before[name])
            new_cpu = statistics.median(r["cpu"] for r in results[name])
            print(f"| {name} | {SCENARIOS[name][0]} | {old_cpu:.2f} | {new_cpu:.2f} "
                  f"| {new_cpu / old_cpu:.2f} |")  # fmt: skip
    print("| scenario | robots | simulated s | real-time factor | wall s | CPU s | ms per step "
          "| peak MB |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    points = []
    for name in names:
        runs = results[name]
        wall = statistics.median(r["wall"] for r in runs)
        cpu = statistics.median(r["cpu"] for r in runs)
        sim = statistics.median(r["sim"] for r in runs)
        steps = statistics.median(r["steps"] for r in runs)
        peak = max(r["peak_mb"] for r in runs)
        per_step = cpu / steps * 1000
        n = SCENARIOS[name][0]
        points.append((n, per_step))
        print(f"| {name} | {n} | {sim:g} | {sim / wall:.3g}x | {wall:.2f} | {cpu:.2f} | "
              f"{per_step:.2f} | {peak:.0f} |")  # fmt: skip
    if len(points) >= 2:
        print(f"cost per step ~ N^{fit_exponent(points):.2f} (log-log least squares)")
    if args.figure is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 3.6))
        ax.loglog([n for n, _ in points], [c for _, c in points], "o", label="measured")
        if len(points) >= 2:
            # The least-squares line in log-log space (its slope is the exponent).
            k = fit_exponent(points)
            xs = [math.log(n) for n, _ in points]
            ys = [math.log(c) for _, c in points]
            c0 = statistics.fmean(ys) - k * statistics.fmean(xs)
            ends = [points[0][0], points[-1][0]]
            ax.loglog(ends, [math.exp(c0 + k * math.log(n)) for n in ends], "--",
                      label=f"fit: cost ~ N^{k:.2f}")  # fmt: skip
            ax.legend()
        ax.set_xlabel("robots")
        ax.set_ylabel("CPU ms per 0.1 s step")
        ax.set_title("Simulation cost against team size")
        ax.grid(True, which="both", alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.figure, dpi=150)
        print(f"figure {args.figure}")


if __name__ == "__main__":
    main()
