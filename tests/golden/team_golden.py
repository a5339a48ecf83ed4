"""Reference outputs of larger teams (the generated scenarios S2, S3, S4), kept to
prove that work on the simulator's speed changes no result at scale.

Each case keeps a digest of :func:`tests.golden.golden.comparable` (the whole summary
without wall time, and the timelines, trajectories and RSSI series) and a few figures
that make a difference readable. ``python -m tests.golden.team_golden --write`` records
them, on the code as it was before a restructuring.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from .golden import ROOT, comparable, write_or_compare

TEAM_GOLDEN_FILE = Path(__file__).with_name("team_golden.json")
SCENARIOS = ROOT / "data" / "scenarios"


def _case(
    scenario: str, behaviour: str, network: str, threshold: str, seed: int, max_time: float
) -> tuple[str, Path, dict[str, Any]]:
    options = {
        "behaviour": behaviour,
        "network": network,
        "threshold": threshold,
        "spl": 25,
        "seed": seed,
        "max_time": max_time,
    }
    name = f"{scenario}-{behaviour}-{network}-{threshold}-spl25-seed{seed}"
    return name, SCENARIOS / scenario / f"{scenario}.yaml", options


#: (name, scenario, options): short missions, long enough that robots meet and re-plan.
CASES: list[tuple[str, Path, dict[str, Any]]] = [
    _case("s2", "nb", "ah", "slt", 1, 150),
    _case("s2", "lf", "ah", "slt", 2, 150),
    _case("s3", "nb", "wlan", "none", 1, 60),
    _case("s4", "nb", "wlan", "none", 1, 30),
]


def run_team_case(scenario: Path, options: dict[str, Any]) -> dict[str, Any]:
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import run_mission

    result = comparable(run_mission(make_config(None, scenario=scenario, **options)))
    blob = json.dumps(result, sort_keys=True).encode()
    return {
        "sha256": hashlib.sha256(blob).hexdigest(),
        "sim_time_s": result["sim_time_s"],
        "tasks_completed": result["mission"]["tasks_completed"],
        "near_collisions": result["mission"]["near_collisions"],
    }


def main() -> None:
    results = {name: run_team_case(path, options) for name, path, options in CASES}
    write_or_compare(results, TEAM_GOLDEN_FILE, __doc__)


if __name__ == "__main__":
    main()
