"""Live-mode benchmarks (issue 7): prints Markdown tables for BENCHMARKS.md.

* ``loopback`` — a 3-robot live mission of S1 (world + 3 agent processes over Zenoh on
  loopback): pose-message latency between agent processes (p50/p99 of every pose
  every agent received) and the CPU the processes used (CPU s / wall s, i.e. cores),
  at ``--speed`` (default 1: real time), limited to ``--max-time`` simulated s.
* ``netns`` — pose-message age between two peers in separate network namespaces
  joined by veth links, with nftables random drop on each input hook, for kernel loss
  0/20/30/50 % over Zenoh TCP and UDP (needs root, ``ip`` and ``nft``).

    .venv/bin/python benchmarks/bench_live.py loopback [--speed 1] [--max-time 120]
    .venv/bin/python benchmarks/bench_live.py netns [--seconds 20] [--rate 20]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
S1 = ROOT / "data" / "scenarios" / "s1.yaml"
PROBE = ROOT / "tests" / "live" / "probe_node.py"


def machine() -> str:
    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}"
    )


def loopback(speed: float, max_time: float, behaviour: str) -> None:
    from mrcomm.live.launcher import LiveTeam
    from mrcomm.live.settings import LiveSettings
    from mrcomm.net.zenoh_config import make_options
    from mrcomm.run.config import make_config

    run = make_config(None, scenario=S1, behaviour=behaviour, max_time=max_time)
    with tempfile.TemporaryDirectory(prefix="bench-live-") as tmp:
        settings = LiveSettings(run, make_options(), Path(tmp), speed=speed)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        started = time.monotonic()
        with LiveTeam(settings) as team:
            team.start()
            team.wait()
            wall = time.monotonic() - started
            result, report = team.collect()
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    latency = report["pose_latency_ms"]
    mission_wall = result.wall_time_s
    print(f"machine: {machine()}")
    print()
    print(
        "| case | speed | sim s | mission wall s | pose latency p50 / p99 (ms) | poses | "
        "CPU s (all 4 processes, incl. start-up) | cores used |"
    )
    print("|---|---|---|---|---|---|---|---|")
    print(
        f"| S1 WLAN {behaviour.upper()} SPL0, 3 robots | {speed:g}x | {result.sim_time_s:.0f} | "
        f"{mission_wall:.1f} | {latency['p50']} / {latency['p99']} | {latency['n']} | "
        f"{cpu:.1f} | {cpu / wall:.2f} (over {wall:.0f} s) |"
    )


def netns(seconds: float, rate: float) -> None:
    sys.path.insert(0, str(ROOT))
    from tests.live.netns import Netns

    print(f"machine: {machine()}")
    print()
    print("| kernel loss | protocol | poses sent | received | age p50 (ms) | age p95 (ms) |")
    print("|---|---|---|---|---|---|")
    for protocol in ("tcp", "udp"):
        for loss in (0, 20, 30, 50):
            with Netns(("a", "b")) as net:
                net.set_faults("a", loss=loss)
                net.set_faults("b", loss=loss)
                procs = [
                    subprocess.Popen(
                        [
                            *net.wrapper(me),
                            sys.executable,
                            str(PROBE),
                            me,
                            f"{protocol}/{net.ip[me]}:7447",
                            f"{protocol}/{net.ip[peer]}:7447",
                            str(seconds),
                            str(rate),
                            protocol,
                        ],
                        stdout=subprocess.PIPE,
                        text=True,
                    )
                    for me, peer in (("a", "b"), ("b", "a"))
                ]
                ages: list[float] = []
                sent = received = 0
                for proc in procs:
                    out, _ = proc.communicate(timeout=seconds + 120)
                    for raw in out.splitlines():
                        line = json.loads(raw)
                        if "age" in line:
                            ages.append(line["age"] * 1000.0)
                        elif "sent" in line:
                            sent += int(line["sent"])
                        else:
                            received += 1
            p50, p95 = (np.percentile(ages, q) if ages else float("nan") for q in (50, 95))
            print(
                f"| {loss} % | {protocol.upper()} | {sent} | {received} | {p50:.1f} | {p95:.1f} |"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    lb = sub.add_parser("loopback")
    lb.add_argument("--speed", type=float, default=1.0)
    lb.add_argument("--max-time", type=float, default=120.0)
    lb.add_argument("--behaviour", default="nb")
    ns = sub.add_parser("netns")
    ns.add_argument("--seconds", type=float, default=20.0)
    ns.add_argument("--rate", type=float, default=20.0)
    args = parser.parse_args()
    if args.what == "loopback":
        loopback(args.speed, args.max_time, args.behaviour)
    else:
        netns(args.seconds, args.rate)


if __name__ == "__main__":
    main()
