"""Two source trees at once, one on each core, the cores swapped every round: the ratio
of their CPU times for one scenario.

On a shared VM whose speed drifts by 10-30 % within minutes, runs one after the other
(``bench_scale.py --old``) can lose a 5 % difference in the drift. Two runs at the same
moment meet the same drift, and swapping cores each round cancels a difference
between the cores. Needs two cores (Linux, ``taskset``).

Each child is ``bench_scale.start_case``'s (NB · WLAN · SPL 25 · seed 1 unless
``--options`` gives other ``make_config`` options as JSON, the simulated time given)
with ``PYTHONPATH`` set to the tree's ``src``, on the tree's own bundled scenario file
(this one's when it has none): a scenario's ``robot`` section may name
parameters an older tree does not know.

Run: ``.venv/bin/python benchmarks/bench_pair.py /tmp/mrcomm-old . --scenario campus1000
--sim-time 20 --rounds 4``; on the radio with the shared channel: ``--options
'{"network": "radio", "behaviour": "lf", "threshold": "slt", "params": {"network":
{"channel": "shared"}}}'``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_scale import ROOT, SCENARIOS, result_of, start_case


def _json_object(text: str) -> dict[str, object]:
    """``--options``: a JSON object, or argparse's one-line error (exit status 2)."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as error:
        raise argparse.ArgumentTypeError(f"not JSON: {error}") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError("must be a JSON object of make_config options")
    return value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("first", type=Path, help="a source tree (e.g. a git worktree)")
    parser.add_argument("second", type=Path, help="another source tree")
    parser.add_argument("--scenario", choices=sorted(SCENARIOS), default="s4")
    parser.add_argument(
        "--sim-time", type=float, default=60.0, help="0: each mission to its end or limit"
    )
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument(
        "--options", type=_json_object, default={}, help="make_config options (JSON object)"
    )
    args = parser.parse_args()
    if (os.cpu_count() or 1) < 2:
        raise SystemExit("needs two cores")
    scenario = SCENARIOS[args.scenario][1]
    first_own, second_own = (
        tree / scenario.relative_to(ROOT) for tree in (args.first, args.second)
    )
    first_path = first_own if first_own.exists() else scenario
    second_path = second_own if second_own.exists() else scenario
    print(
        f"{args.scenario} {json.dumps(args.options)}, {args.sim_time:g} s simulated; "
        f"load {os.getloadavg()}"
    )
    rounds: list[tuple[float, float]] = []
    for k in range(args.rounds):
        cores = (0, 1) if k % 2 == 0 else (1, 0)
        a = start_case(first_path, args.sim_time, args.first, cores[0], args.options)
        b = start_case(second_path, args.sim_time, args.second, cores[1], args.options)
        ra, rb = result_of(a), result_of(b)
        rounds.append((ra["cpu"], rb["cpu"]))
        print(
            f"round {k + 1}: CPU s {ra['cpu']:.2f} / {rb['cpu']:.2f}, "
            f"wall s {ra['wall']:.2f} / {rb['wall']:.2f}, "
            f"simulated s {ra['sim']:.1f} / {rb['sim']:.1f}, "
            f"real-time factor {ra['sim'] / ra['wall']:.3f} / {rb['sim'] / rb['wall']:.3f}, "
            f"peak MB {ra['peak_mb']:.0f} / {rb['peak_mb']:.0f}",
            flush=True,
        )
    ratio = statistics.median(b / a for a, b in rounds)
    first = statistics.median(a for a, _ in rounds)
    second = statistics.median(b for _, b in rounds)
    print(f"median CPU s {first:.2f} / {second:.2f}; second / first, median of rounds {ratio:.3f}")
    print(f"load after {os.getloadavg()}")


if __name__ == "__main__":
    main()
