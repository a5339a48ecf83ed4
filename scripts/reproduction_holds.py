"""Where an LF leader's hold time comes from on S1: the links that warn while it holds.

For each threshold (SLT, SSD) this runs LF missions on S1 · AH with the original robots'
profile (data/experiments/reproduction-original.yaml), and at every step a leader holds
looks at its links that warn in the link model: how far the follower is, whether the two
see each other, and what the follower is doing. docs/REPRODUCTION.md ("SSD against SLT")
quotes its output.

Usage: ``python scripts/reproduction_holds.py [--spl 0] [--seeds 8]``
"""

from __future__ import annotations

import argparse
import collections

from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import ACTIVITY
from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission

SCENARIO = "data/scenarios/s1.yaml"
#: The original robots' profile (reproduction-original.yaml's params).
PROFILE = {"behaviour": {"judge_poses": "on_receipt", "lf": {"follow_distance": 0.65}}}


def holds(threshold: str, spl: float, seeds: int, resources: ScenarioResources) -> None:
    distance: collections.Counter[float] = collections.Counter()
    follower: collections.Counter[tuple[str, str]] = collections.Counter()
    hold_steps = 0
    for seed in range(1, seeds + 1):
        config = make_config(
            None, scenario=SCENARIO, network="ah", spl=spl, behaviour="lf",
            threshold=threshold, seed=seed, params=PROFILE,
        )  # fmt: skip
        mission = Mission(config, resources)
        robots = mission.robot_ids
        while not mission.finished and mission.now < config.max_time:
            mission.step()
            links = mission.last_links
            for i, robot in enumerate(robots):
                if mission.timelines[robot].state(ACTIVITY) != L.LEADER_DISCONNECT:
                    continue
                hold_steps += 1
                for j, mate in enumerate(robots):
                    if j == i or not links.warning[i, j]:
                        continue
                    distance[round(float(links.distance[i, j]) * 2) / 2] += 1
                    sight = links.line_of_sight
                    seen = "-" if sight is None else "in sight" if sight[i, j] else "obstructed"
                    follower[(seen, str(mission.timelines[mate].state(ACTIVITY)))] += 1
    total = sum(distance.values()) or 1
    print(f"{threshold}: the leader holds {hold_steps * config.dt / seeds:.1f} s a mission")
    shares = {
        f"{d:.1f}": round(c / total, 3) for d, c in sorted(distance.items()) if c / total > 0.01
    }
    print("  a warned follower's distance (m, half-metre bins):", shares)
    states = {f"{s} / {a}": round(c / total, 3) for (s, a), c in follower.most_common(6)}
    print("  its sight and activity:", states)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spl", type=float, default=0.0, help="simulated packet loss, %%")
    parser.add_argument("--seeds", type=int, default=8, help="missions per threshold")
    args = parser.parse_args()
    resources = ScenarioResources.load(SCENARIO)
    for threshold in ("slt", "ssd"):
        holds(threshold, args.spl, args.seeds, resources)


if __name__ == "__main__":
    main()
