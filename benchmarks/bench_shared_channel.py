"""What the shared channel does to a team, and what it costs (issue 44).

    .venv/bin/python benchmarks/bench_shared_channel.py cost [--repeats 5]
    .venv/bin/python benchmarks/bench_shared_channel.py team [--seeds 1 2 3] [--max-time S]

``cost``: S1 · LF · SLT · SPL 50 on AH, on the radio with each sender's queue and on the
radio with the shared channel, interleaved seed by seed on one pinned core: the
real-time factor (simulated s / wall s) and CPU time of each, and the shared channel's
cost against AH (paired by seed).

``team``: S4 (100 robots) · radio · LF · SLT, the same seeds with each channel (or the
channels given, so that two processes can take one each, on the two cores): the
mission (simulated time, timed out, tasks completed and reported, near collisions),
pose delivery (received over received + every drop, among mates in range), the poses
lost to collisions and to the queue, the mean pose delay, the channel load (airtime
of all poses / mission time) and the real-time factor with CPU time (``--max-time``:
only the mission's first seconds). Prints Markdown tables for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path
from typing import Any

from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import run_mission

ROOT = Path(__file__).resolve().parents[1]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"
S4 = ROOT / "data" / "scenarios" / "s4" / "s4.yaml"
SHARED = {"network": {"channel": "shared"}}


def _pin(last: bool = False) -> None:
    """One core: the first (cost), or the last (team: the two can run side by side)."""
    if hasattr(os, "sched_setaffinity"):
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cores[-1] if last else cores[0]})


def _timed(config: Any, resources: ScenarioResources) -> tuple[Any, float, float]:
    cpu = time.process_time()
    result = run_mission(config, resources)
    return result, result.wall_time_s, time.process_time() - cpu


def cost(repeats: int) -> None:
    _pin()
    resources = ScenarioResources.load(S1)
    cases = {
        "AH": {"network": "ah"},
        "radio, queue": {"network": "radio"},
        "radio, shared": {"network": "radio", "params": SHARED},
    }
    factors: dict[str, list[float]] = {name: [] for name in cases}
    cpus: dict[str, list[float]] = {name: [] for name in cases}
    print(f"load before: {os.getloadavg()}")
    for seed in range(1, repeats + 1):
        for name, options in cases.items():
            config = make_config(
                None, scenario=S1, seed=seed, spl=50, behaviour="lf", threshold="slt",
                **options,  # type: ignore[arg-type]
            )  # fmt: skip
            result, wall, cpu = _timed(config, resources)
            factors[name].append(result.sim_time_s / wall)
            cpus[name].append(result.sim_time_s / cpu)
    print(f"load after: {os.getloadavg()}")
    print("| S1 · LF · SLT · SPL 50 | real-time factor (median) | min..max | per CPU s (median) |")
    print("|---|---|---|---|")
    for name in cases:
        f = factors[name]
        print(
            f"| {name} | **{statistics.median(f):.0f}×** | {min(f):.0f}..{max(f):.0f} | "
            f"{statistics.median(cpus[name]):.0f}× |"
        )
    paired = [
        100 * (1 - s / a) for a, s in zip(factors["AH"], factors["radio, shared"], strict=True)
    ]
    print(
        f"\nThe shared channel costs {statistics.median(paired):.1f} % of AH's real-time factor "
        f"(median of the seeds' pairs; range {min(paired):.1f}..{max(paired):.1f} %; target 35 %)"
    )


def _pose_figures(result: Any) -> dict[str, float]:
    pose = result.messages.get("pose", {})
    received = pose.get("received", 0)
    lost = sum(pose.get(k, 0) for k in ("dropped_loss", "dropped_radio", "dropped_queue",
                                           "dropped_collision"))  # fmt: skip
    return {
        "delivery": received / (received + lost) if received + lost else float("nan"),
        "collisions": pose.get("dropped_collision", 0) / max(received + lost, 1),
        "queue": pose.get("dropped_queue", 0) / max(received + lost, 1),
        "delay_ms": 1e3 * pose.get("delay_mean_s", 0.0),
        "load": pose.get("airtime_s", float("nan")) / result.sim_time_s,
    }


def team(seeds: list[int], max_time: float | None, channels: list[str], last: bool) -> None:
    _pin(last=last)
    resources = ScenarioResources.load(S4)
    print(f"load before: {os.getloadavg()}")
    print(
        "| channel | seed | simulated (s) | timed out | tasks completed | tasks reported | "
        "near collisions | pose delivery | lost to collisions | lost to the queue | "
        "pose delay (ms) | pose airtime / s | real-time factor | per CPU s |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for seed in seeds:
        for channel in channels:
            extra: dict[str, Any] = {"max_time": max_time} if max_time else {}
            config = make_config(
                None, scenario=S4, seed=seed, network="radio", behaviour="lf",
                threshold="slt", params={"network": {"channel": channel}}, **extra,
            )  # fmt: skip
            result, wall, cpu = _timed(config, resources)
            m = result.mission
            p = _pose_figures(result)
            tasks = len(resources.scenario.tasks) - len(m.get("failed_tasks") or [])
            print(
                f"| {channel} | {seed} | {result.sim_time_s:.0f} | {m.get('timed_out')} | "
                f"{m.get('tasks_completed')} | {tasks}/{len(resources.scenario.tasks)} | "
                f"{m.get('near_collisions')} | {p['delivery']:.3f} | "
                f"{p['collisions']:.3f} | {p['queue']:.3f} | {p['delay_ms']:.2f} | "
                f"{p['load']:.2f} | {result.sim_time_s / wall:.2f}× | "
                f"{result.sim_time_s / cpu:.2f}× |",
                flush=True,
            )
    print(f"load after: {os.getloadavg()}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    c = sub.add_parser("cost")
    c.add_argument("--repeats", type=int, default=5)
    t = sub.add_parser("team")
    t.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    t.add_argument("--max-time", type=float, default=None)
    t.add_argument("--channels", nargs="+", default=["queue", "shared"])
    t.add_argument(
        "--first-core", action="store_true", help="pin to the first core (else the last)"
    )
    args = parser.parse_args()
    if args.what == "cost":
        cost(args.repeats)
    else:
        team(args.seeds, args.max_time, args.channels, last=not args.first_core)


if __name__ == "__main__":
    main()
