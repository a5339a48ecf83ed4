"""Where an LF leader's hold time comes from on S1: the links that warn while it holds.

For each threshold (SLT, SSD) this runs the LF · AH configuration of the original robots'
profile (data/experiments/reproduction-original.yaml: S1 and its parameters), and at
every step a leader holds looks at its links that warn in the link model: how far the
follower is, whether the two see each other, and what the follower is doing.
docs/REPRODUCTION.md ("SSD against SLT") quotes its output.

Usage: ``python scripts/reproduction_holds.py [--spl 0] [--seeds 8]``
"""

from __future__ import annotations

import argparse
import collections
import sys

from mrcomm.experiment.schema import Configuration, load_experiment
from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import ACTIVITY
from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission

#: The original robots' profile: its LF configurations on AH are the ones studied.
PROFILE = "data/experiments/reproduction-original.yaml"


def profile_configuration(
    threshold: str, spl: float, behaviour: str = "lf", network: str = "ah"
) -> Configuration:
    """The profile's configuration with ``behaviour`` (LF), ``network`` (AH),
    ``threshold`` and ``spl``."""
    for configuration in load_experiment(PROFILE).configurations:
        config = configuration.config
        if (config.behaviour, config.network, config.threshold, config.spl) == (
            behaviour, network, threshold, spl,
        ):  # fmt: skip
            return configuration
    name = f"{behaviour.upper()} · {network.upper()} · {threshold} · SPL {spl:g}"
    print(f"{PROFILE}: no {name} configuration", file=sys.stderr)
    raise SystemExit(2)


def holds(threshold: str, spl: float, seeds: int) -> None:
    distance: collections.Counter[float] = collections.Counter()
    follower: collections.Counter[tuple[str, str]] = collections.Counter()
    hold_steps = 0
    base = profile_configuration(threshold, spl).config
    resources = ScenarioResources.load(base.scenario)
    for seed in range(1, seeds + 1):
        config = base.model_copy(update={"seed": seed})
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
    print(f"{threshold}: the leader holds {hold_steps * base.dt / max(seeds, 1):.1f} s a mission")
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
    for threshold in ("slt", "ssd"):
        holds(threshold, args.spl, args.seeds)


if __name__ == "__main__":
    main()
