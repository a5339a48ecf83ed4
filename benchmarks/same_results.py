"""Whole team missions on two source trees: does a change that should change no result
change one?

The team digests kept in ``tests/golden/team_golden.json`` cover the first 30-150 s of
four team missions (quick enough for every test run). This script runs whole missions,
to their end or the scenario's limit, of S2 and S3 (NB and LF, WLAN and AH with SLT,
several SPL and seeds) with the code of each tree, in a fresh process pinned to one core,
and compares the digests of their results (``tests.golden.golden.comparable``: the
whole summary without wall time, the timelines, trajectories and RSSI series).

    git worktree add /tmp/mrcomm-old <commit>
    .venv/bin/python benchmarks/same_results.py /tmp/mrcomm-old . [--large]

Exits 1 when any case differs.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

CASES: list[tuple[str, dict[str, object]]] = [
    ("s2", {"behaviour": "nb", "network": "wlan", "threshold": "none", "spl": 25, "seed": 1}),
    ("s2", {"behaviour": "nb", "network": "ah", "threshold": "slt", "spl": 0, "seed": 2}),
    ("s2", {"behaviour": "nb", "network": "ah", "threshold": "slt", "spl": 50, "seed": 3}),
    ("s2", {"behaviour": "lf", "network": "ah", "threshold": "slt", "spl": 25, "seed": 1}),
    ("s2", {"behaviour": "lf", "network": "ah", "threshold": "slt", "spl": 0, "seed": 4}),
    ("s3", {"behaviour": "nb", "network": "wlan", "threshold": "none", "spl": 25, "seed": 1}),
    ("s3", {"behaviour": "lf", "network": "ah", "threshold": "slt", "spl": 25, "seed": 2}),
]

#: With ``--large``: S4 (100 robots; the in-process bus keeps their latest poses), every
#: way poses are delivered (step batches; one by one on the radio's queue channel; frames
#: of the shared channel) and the behaviours that hear them otherwise (LF's AON lease,
#: RPS's first positions), within time limits that keep the radio's runs short.
LARGE_CASES: list[tuple[str, dict[str, object]]] = [
    ("s4", {"behaviour": "nb", "network": "wlan", "threshold": "none", "spl": 25, "seed": 1}),
    ("s4", {"behaviour": "lf", "network": "ah", "threshold": "slt", "spl": 25, "seed": 1,
            "max_time": 600}),
    ("s4", {"behaviour": "rps", "network": "ah", "threshold": "slt", "spl": 25, "seed": 2,
            "max_time": 600}),
    ("s4", {"behaviour": "lf", "network": "radio", "threshold": "slt", "spl": 0, "seed": 1,
            "max_time": 60}),
    ("s4", {"behaviour": "nb", "network": "radio", "threshold": "none", "spl": 0, "seed": 1,
            "max_time": 60, "params": {"network": {"channel": "shared"}}}),
]  # fmt: skip

#: Runs in the child, in the tree's directory (``tests`` is importable from there).
CHILD = """
import json, sys
from pathlib import Path
from tests.golden.team_golden import run_team_case
print(json.dumps(run_team_case(Path(sys.argv[1]), json.loads(sys.argv[2]))))
"""


def run(tree: Path, scenario: str, options: dict[str, object]) -> dict[str, object]:
    """One whole mission with ``tree``'s code and bundled scenario: its digest and figures."""
    tree = tree.resolve()
    # The tree's own example plugin too: the installed one's entry point then loads the
    # tree's version of it (a plugin of a newer tree may not import in an older one).
    path = os.pathsep.join(
        str(p) for p in (tree / "src", tree, tree / "examples" / "mrcomm-repeat")
    )
    env = dict(os.environ, PYTHONPATH=path)
    path = tree / "data" / "scenarios" / scenario / f"{scenario}.yaml"
    command = [sys.executable, "-c", CHILD, str(path), json.dumps(options)]
    if sys.platform.startswith("linux"):
        command = ["taskset", "-c", "0", *command]
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=tree)
    if done.returncode != 0:
        raise SystemExit(f"{tree}: {scenario} {options} failed:\n{done.stderr[-2000:]}")
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("first", type=Path, help="a source tree (e.g. a git worktree)")
    parser.add_argument("second", type=Path, help="another source tree")
    parser.add_argument(
        "--large", action="store_true", help="also S4 (100 robots): see LARGE_CASES"
    )
    args = parser.parse_args()
    differ = 0
    print("| scenario | case | simulated s | tasks | same result |")
    print("|---|---|---|---|---|")
    for scenario, options in CASES + (LARGE_CASES if args.large else []):
        first, second = run(args.first, scenario, options), run(args.second, scenario, options)
        same = first["sha256"] == second["sha256"]
        differ += not same
        case = " · ".join(str(v) for k, v in options.items() if k != "params")
        case += " · shared channel" if "params" in options else ""
        times = (
            f"{first['sim_time_s']}" if same else f"{first['sim_time_s']} / {second['sim_time_s']}"
        )
        print(f"| {scenario} | {case} | {times} | {first['tasks_completed']} "
              f"| {'yes' if same else '**no**'} |")  # fmt: skip
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
