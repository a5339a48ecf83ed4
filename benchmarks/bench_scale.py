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

With ``--options JSON`` (make_config's, over NB · WLAN · SPL 25) every case runs that
configuration instead, e.g. the radio (``'{"network": "radio"}'``) or its shared channel
(``'{"network": "radio", "params": {"network": {"channel": "shared"}}}'``); ``--core``
picks the core the children are pinned to (two benchmarks at once, one per core), and
``--label`` names each configuration in the tables and the figure. ``--replot OUTPUT
--figure PNG`` draws the figure again from a saved output of this script (its printed
table), running nothing.

Run: ``.venv/bin/python benchmarks/bench_scale.py [--repeats 3] [--sim-time 120 | --whole]
[--only s2 --only s3] [--figure docs/figures/scale.png] [--old /tmp/mrcomm-old]
[--options JSON] [--core 1]``
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
from typing import cast

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


def run_case(
    path: Path,
    sim_time: float,
    tree: Path | None = None,
    core: int = 0,
    options: dict[str, object] | None = None,
) -> dict[str, float]:
    """One case in a fresh process on ``core``, waited for."""
    return result_of(start_case(path, sim_time, tree, core, options))


def fit_exponent(points: list[tuple[int, float]]) -> float:
    """Slope of log(cost per step) against log(N)."""
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(c) for _, c in points]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum(
        (x - mx) ** 2 for x in xs
    )


def label_of(options: dict[str, object], prefix: str = "") -> str:
    """A configuration's name in the tables: its options flattened (``network=radio
    params.network.channel=shared``), or the default case's."""
    if not options and not prefix:
        return "NB · WLAN · SPL 25"
    return " ".join(
        label_of(cast(dict[str, object], value), f"{prefix}{key}.")
        if isinstance(value, dict)
        else f"{prefix}{key}={value}"
        for key, value in options.items()
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sim-time", type=float, default=120.0)
    parser.add_argument("--only", action="append", choices=sorted(SCENARIOS))
    parser.add_argument("--whole", action="store_true", help="each mission to its end")
    parser.add_argument("--figure", type=Path)
    parser.add_argument("--old", type=Path, help="an earlier tree to run side by side")
    parser.add_argument(
        "--options",
        type=json.loads,
        action="append",
        help="make_config options (JSON); repeat it to interleave several configurations",
    )
    parser.add_argument("--core", type=int, default=0, help="the core the children run on")
    parser.add_argument(
        "--label", action="append", help="a name for each --options, in order (tables, figure)"
    )
    parser.add_argument(
        "--replot", type=Path, help="draw --figure from a saved output of this script; run nothing"
    )
    args = parser.parse_args()
    if args.replot is not None:
        if args.figure is None:
            raise SystemExit("--replot needs --figure")
        saved = read_table(args.replot)
        if args.label:  # new names for the saved configurations, in order
            saved = [(name, points) for name, (_, points) in zip(args.label, saved, strict=True)]
        draw_figure(saved, args.figure)
        return
    configs: list[dict[str, object]] = args.options or [{}]
    labels: list[str] = args.label or [label_of(c) for c in configs]
    if len(labels) != len(configs):
        raise SystemExit(f"{len(labels)} --label for {len(configs)} configurations")
    names = args.only or list(SCENARIOS)
    if args.whole:
        args.sim_time = 0.0
    span = "whole missions" if args.whole else f"{args.sim_time:g} s simulated"
    print(f"Python {platform.python_version()}, {os.cpu_count()} CPUs, pinned to core "
          f"{args.core}; {' | '.join(labels)}; {span}; "
          f"load {os.getloadavg()}")  # fmt: skip
    cases = [(name, k) for name in names for k in range(len(configs))]
    results: dict[tuple[str, int], list[dict[str, float]]] = {case: [] for case in cases}
    before: dict[tuple[str, int], list[dict[str, float]]] = {case: [] for case in cases}
    for _ in range(args.repeats):
        for name, k in cases:  # interleaved: background load falls on every case alike
            path = SCENARIOS[name][1]
            results[name, k].append(run_case(path, args.sim_time, None, args.core, configs[k]))
            if args.old is not None:
                own = args.old / path.relative_to(ROOT)
                old_path = own if own.exists() else path
                before[name, k].append(
                    run_case(old_path, args.sim_time, args.old, args.core, configs[k])
                )
    print(f"load after: {os.getloadavg()}")
    if args.old is not None:
        print(f"| scenario | robots | configuration | CPU s, {args.old} | CPU s, this tree "
              "| this / old |")  # fmt: skip
        print("|---|---|---|---|---|---|")
        for name, k in cases:
            old_cpu = statistics.median(r["cpu"] for r in before[name, k])
            new_cpu = statistics.median(r["cpu"] for r in results[name, k])
            print(f"| {name} | {SCENARIOS[name][0]} | {labels[k]} | {old_cpu:.2f} "
                  f"| {new_cpu:.2f} | {new_cpu / old_cpu:.2f} |")  # fmt: skip
    print("| scenario | robots | configuration | simulated s | real-time factor | wall s | CPU s "
          "| ms per step | per step, against the first | peak MB |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|")
    series: list[list[tuple[int, float]]] = [[] for _ in configs]
    for name, k in cases:
        runs = results[name, k]
        wall = statistics.median(r["wall"] for r in runs)
        cpu = statistics.median(r["cpu"] for r in runs)
        sim = statistics.median(r["sim"] for r in runs)
        steps = statistics.median(r["steps"] for r in runs)
        peak = max(r["peak_mb"] for r in runs)
        per_step = cpu / steps * 1000
        n = SCENARIOS[name][0]
        series[k].append((n, per_step))
        # Missions of two configurations may differ in length: compare the cost per step.
        first = series[0][-1][1]
        print(f"| {name} | {n} | {labels[k]} | {sim:g} | {sim / wall:.3g}x | "
              f"{wall:.2f} | {cpu:.2f} | {per_step:.2f} | {per_step / first:.2f} | "
              f"{peak:.0f} |")  # fmt: skip
    for k, points in enumerate(series):
        if len(points) >= 2:
            print(f"{labels[k]}: cost per step ~ N^{fit_exponent(points):.2f} "
                  "(log-log least squares)")  # fmt: skip
    if args.figure is not None:
        draw_figure([(labels[k], points) for k, points in enumerate(series)], args.figure)


def read_table(path: Path) -> list[tuple[str, list[tuple[int, float]]]]:
    """The (configuration, [(robots, ms per step)]) series of a table this script printed
    (its output kept in a file), in the order the configurations first appear."""
    series: dict[str, list[tuple[int, float]]] = {}
    for line in path.read_text().splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) != 10 or not cells[1].isdigit():
            continue  # not a row of the main table
        series.setdefault(cells[2], []).append((int(cells[1]), float(cells[7])))
    if not series:
        raise SystemExit(f"{path}: no table of bench_scale.py's in it")
    return list(series.items())


def draw_figure(series: list[tuple[str, list[tuple[int, float]]]], path: Path) -> None:
    """Cost per step against team size on log-log axes, each series with its fit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.6))
    for name, points in series:
        dots = ax.loglog([n for n, _ in points], [c for _, c in points], "o", label=name)
        if len(points) >= 2:
            # The least-squares line in log-log space (its slope is the exponent).
            slope = fit_exponent(points)
            xs = [math.log(n) for n, _ in points]
            ys = [math.log(c) for _, c in points]
            c0 = statistics.fmean(ys) - slope * statistics.fmean(xs)
            ends = [points[0][0], points[-1][0]]
            ax.loglog(ends, [math.exp(c0 + slope * math.log(n)) for n in ends], "--",
                      color=dots[0].get_color(),
                      label=f"fit: cost ~ N^{slope:.2f}")  # fmt: skip
    ax.legend(fontsize="small", loc="upper left")
    ax.set_xlabel("robots")
    ax.set_ylabel("CPU ms per 0.1 s step")
    ax.set_title("Simulation cost against team size")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    print(f"figure {path}")


if __name__ == "__main__":
    main()
