"""Reference outputs of a fixed set of S1 runs, kept to prove that restructurings change
no result.

``python -m tests.golden.golden --write`` records them (do it before a restructuring
starts, on the code as it was; a re-record of changed results needs ``--why``, logged in
``rerecords.json``: see :mod:`tests.golden.rerecord`); ``tests/golden/test_golden.py``
runs the same cases and compares. Each case keeps the full ``run --json`` summary (minus
wall time, and minus the configuration echo, whose shape may grow) and a digest of what
the summary does not show: the timelines, the trajectories and the RSSI series.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
GOLDEN_FILE = Path(__file__).with_name("s1_golden.json")
SCENARIO = ROOT / "data" / "scenarios" / "s1.yaml"
TRACE = ROOT / "data" / "traces" / "s1_synthetic_esd.csv"


def cases() -> list[dict[str, Any]]:
    """NB and LF x WLAN/AH x none/SLT/SSD/ESD x SPL 0/50 x seeds 1, 2 (SSD is ad-hoc only)."""
    out = []
    for behaviour, network, threshold, spl, seed in itertools.product(
        ("nb", "lf"), ("wlan", "ah"), ("none", "slt", "ssd", "esd"), (0, 50), (1, 2)
    ):
        if threshold == "ssd" and network != "ah":
            continue
        out.append(
            {
                "behaviour": behaviour,
                "network": network,
                "threshold": threshold,
                "spl": spl,
                "seed": seed,
            }
        )
    return out


def case_key(case: dict[str, Any]) -> str:
    return "{behaviour}-{network}-{threshold}-spl{spl}-seed{seed}".format(**case)


#: Team metrics added after the references were recorded (new values, not changed ones:
#: they have their own tests), left out of the comparison.
ADDED_MISSION_METRICS = (
    "tasks_per_minute",
    "assigner_connected",
    "largest_group_mean",
    "largest_group_min",
)


#: Near collisions checked against ground truth, per robot and team (added later).
ADDED_TRUTH_METRICS = (
    "near_collisions_confirmed",
    "near_collisions_false",
    "near_collisions_missed",
)


#: Per robot, added later: waits at one-lane passages (none in S1: its scenario names
#: no one-lane width).
ADDED_ROBOT_METRICS = ("queued",)


def without_added(summary: dict[str, Any]) -> dict[str, Any]:
    for key in (*ADDED_MISSION_METRICS, *ADDED_TRUTH_METRICS):
        summary["mission"].pop(key, None)
    for robot in summary["robots"].values():
        for key in (*ADDED_TRUTH_METRICS, *ADDED_ROBOT_METRICS):
            robot.pop(key, None)
    return summary


def comparable(result: Any) -> dict[str, Any]:
    """What must stay identical: the summary without wall time and config echo, plus a
    digest of timelines, trajectories and RSSI samples."""
    summary = without_added(dict(result.summary()))
    summary.pop("wall_time_s")
    config = summary.pop("config")
    summary["label"] = config["label"]
    hidden = {
        "timelines": {
            rid: {
                "intervals": [(i.track, i.label, i.start, i.end) for i in tl.intervals],
                "events": [(e.time, e.label, sorted(e.data.items())) for e in tl.events],
            }
            for rid, tl in result.timelines.items()
        },
        "trajectories": {rid: list(t) for rid, t in result.trajectories.items()},
        "rssi": result.rssi_series,
    }
    blob = json.dumps(hidden, sort_keys=True, default=str).encode()
    summary["hidden_sha256"] = hashlib.sha256(blob).hexdigest()
    return json.loads(json.dumps(summary, sort_keys=True))


def run_case(case: dict[str, Any], world: Any = None) -> dict[str, Any]:
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import run_mission

    options = dict(case)
    if case["threshold"] == "esd":
        options["rssi_trace"] = TRACE
    config = make_config(None, scenario=SCENARIO, **options)
    return comparable(run_mission(config, world))


def write_or_compare(results: dict[str, Any], path: Path, doc: str | None) -> None:
    """The command line of a reference file: ``--write`` records ``results`` in
    ``path``; without it they are compared with what it holds."""
    parser = argparse.ArgumentParser(description=doc)
    parser.add_argument("--write", action="store_true", help="record the reference outputs")
    parser.add_argument("--why", help="the behaviour change a re-record is for (logged)")
    args = parser.parse_args()
    if args.write:
        from .rerecord import write_logged

        write_logged(results, path, args.why)
    else:
        golden = json.loads(path.read_text())
        bad = [k for k, v in results.items() if golden.get(k) != v]
        print(f"{len(results) - len(bad)} of {len(results)} identical; differ: {bad}")


def main() -> None:
    write_or_compare({case_key(c): run_case(c) for c in cases()}, GOLDEN_FILE, __doc__)


if __name__ == "__main__":
    main()
