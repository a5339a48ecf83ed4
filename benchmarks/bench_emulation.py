"""What the kernel and Zenoh make of the network model's decisions (``mrcomm live
--emulate``): one S1 mission per transport (TCP, UDP) with every process in its own
network namespace, the world setting each ordered pair's packet drops from the model.

Prints, per transport, the model's decisions against what the kernel did (packets seen
and dropped per decision), what reached the agents (pose messages, latency, statuses
lost) and the same mission simulated; draws, per ordered pair, the model's delivery
probability over mission time against the kernel's measured delivery ratio (5 s
windows). Needs root, ``ip`` and ``nft``.

    .venv/bin/python benchmarks/bench_emulation.py --figure docs/figures/emulation_delivery.png
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"
WINDOW = 5.0  # simulated s per measured point
_CLI = "from mrcomm.cli.main import app; app()"


def live(record: Path, protocol: str, options: dict[str, str]) -> dict[str, Any]:
    args = [sys.executable, "-c", _CLI, "live", str(S1), "--emulate", "--insecure", "--json"]
    args += ["--record-dir", str(record), "--protocol", protocol]
    for key, value in options.items():
        args += [f"--{key}", value]
    done = subprocess.run(args, capture_output=True, text=True, timeout=1200)
    if done.returncode != 0:
        raise SystemExit(done.stderr[-2000:])
    return json.loads(done.stdout)


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def kernel_periods(record: Path) -> list[dict[str, Any]]:
    lines = []
    for path in sorted(record.glob("world.*.jsonl")):
        for raw in path.read_text().splitlines():
            line = json.loads(raw)
            if line["k"] == "kernel":
                lines.append(line)
    return lines


def by_decision(periods: list[dict[str, Any]]) -> dict[int, list[int]]:
    out: dict[int, list[int]] = {}
    for period in periods:
        for _a, _b, permille, seen, dropped in period["pairs"]:
            counts = out.setdefault(permille, [0, 0])
            counts[0] += seen
            counts[1] += dropped
    return out


def simulated(options: dict[str, str], seed: int) -> dict[str, Any]:
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import run_mission

    config = make_config(
        None,
        scenario=S1,
        seed=seed,
        network=options["network"],
        behaviour=options["behaviour"],
        threshold=options["threshold"],
        spl=float(options["spl"]),
    )
    return run_mission(config).summary()


def figure(periods: list[dict[str, Any]], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pairs = sorted({(a, b) for p in periods for a, b, *_ in p["pairs"]})
    fig, axes = plt.subplots(len(pairs), 1, figsize=(7.0, 1.25 * len(pairs)), sharex=True)
    for ax, pair in zip(axes, pairs, strict=True):
        times, model = [], []
        windows: dict[int, list[int]] = {}
        for p in periods:
            for a, b, permille, seen, dropped in p["pairs"]:
                if (a, b) != pair:
                    continue
                times += [p["t0"], p["t1"]]
                model += [1 - permille / 1000] * 2
                counts = windows.setdefault(int(p["t0"] // WINDOW), [0, 0])
                counts[0] += seen
                counts[1] += dropped
        ax.plot(times, model, color="0.3", lw=1.0, label="model: delivery probability")
        xs = [(k + 0.5) * WINDOW for k, (seen, _) in sorted(windows.items()) if seen]
        ys = [1 - d / s for _, (s, d) in sorted(windows.items()) if s]
        ax.plot(xs, ys, "o", ms=2.5, color="tab:blue", label=f"kernel: delivered ({WINDOW:g} s)")
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel(f"{pair[0][-1]}→{pair[1][-1]}", rotation=0, labelpad=14)
        ax.set_yticks([0, 0.75, 1])
    axes[0].legend(loc="lower left", fontsize=7, ncols=2)
    axes[0].set_title(title, fontsize=9)
    axes[-1].set_xlabel("mission time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    print(f"figure: {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--speed", default="5")
    parser.add_argument("--seed", default="1")
    parser.add_argument("--behaviour", default="nb")
    parser.add_argument("--spl", default="25")
    parser.add_argument("--figure", type=Path, default=None)
    args = parser.parse_args()
    options = {
        "network": "ah",
        "behaviour": args.behaviour,
        "threshold": "none" if args.behaviour == "nb" else "slt",
        "spl": args.spl,
        "seed": args.seed,
        "speed": args.speed,
    }
    print(f"load before: {os.getloadavg()}")
    sim = simulated(options, int(args.seed))
    pose = sim["messages"]["pose"]
    heard = pose["received"] + pose["dropped_loss"] + pose["dropped_range"]
    print(
        f"simulated (seed {args.seed}): failed tasks {sim['mission']['failed_tasks']}, pose "
        f"deliveries {pose['received']}/{heard} = {pose['received'] / heard:.3f} "
        f"(range {pose['dropped_range']}, SPL {pose['dropped_loss']})"
    )
    for protocol in ("tcp", "udp"):
        with tempfile.TemporaryDirectory() as directory:
            record = Path(directory)
            started, cpu = time.monotonic(), children_cpu()
            result = live(record, protocol, options)
            wall = time.monotonic() - started
            cpu = children_cpu() - cpu
            periods = kernel_periods(record)
            decided = by_decision(periods)
            pose = result["messages"]["pose"]
            latency = result["live"]["pose_latency_ms"]
            receivers = len(result["robots"])  # its mates and the task assigner
            print(
                f"{protocol}: {wall:.0f} s wall, {cpu:.0f} s CPU (all processes); "
                f"failed tasks {result['mission']['failed_tasks']}; "
                f"poses sent {pose['sent']}, received {pose['received']} of "
                f"{pose['sent'] * receivers} sent to mates "
                f"({pose['received'] / (pose['sent'] * receivers):.3f}); latency ms p50 "
                f"{latency['p50']}, p99 {latency['p99']}, max {latency['max']}"
            )
            for permille, (seen, dropped) in sorted(decided.items()):
                print(
                    f"  model drop {permille / 10:g} %: kernel saw {seen} packets, dropped "
                    f"{dropped} ({dropped / seen if seen else 0:.3f})"
                )
            if protocol == "tcp" and args.figure is not None:
                title = (
                    f"S1 · AH · {args.behaviour.upper()} · SPL {args.spl} · seed {args.seed}, "
                    f"--emulate over TCP at --speed {args.speed}"
                )
                figure(periods, args.figure, title)
    print(f"load after: {os.getloadavg()}; this process's CPU {time.process_time():.1f} s")


if __name__ == "__main__":
    main()
