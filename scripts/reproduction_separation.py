"""The maximum separation as the robots heard it, beside the true one, on S1.

A candidate mechanism for the original's LF team stretching to "just over 10 m" under loss
(docs/REPRODUCTION.md, "What is left"): the original's robots recorded their own metrics
(thesis line 2113), each from its own pose and the list of its mates' last received
poses (line 791), so a separation it recorded could be to a mate's old pose. This runs
the original robots' profile (data/experiments/reproduction-original.yaml) and at every
step takes each robot's distance from its true position to every mate's last pose it
received, beside MRComm's own metric (``max_separation``, the true distance as the run's
link recorder keeps it).

Usage: ``python scripts/reproduction_separation.py [--behaviour lf] [--network ah] [--seeds 6]``
"""

from __future__ import annotations

import argparse
import math
import statistics

from mrcomm.run.resources import ScenarioResources
from mrcomm.sim.mission import Mission
from reproduction_holds import profile_configuration

#: The loss levels of the original's design.
SPLS = (0.0, 25.0, 50.0, 75.0)


def separations(behaviour: str, network: str, spl: float, seeds: int) -> tuple[float, float]:
    """The mean over ``seeds`` missions of the maximum true separation and of the maximum
    separation as heard (m), for the profile's ``behaviour`` · ``network`` · SLT · ``spl``."""
    base = profile_configuration("slt", spl, behaviour, network).config
    resources = ScenarioResources.load(base.scenario)
    true_maxima, heard_maxima = [], []
    for seed in range(1, seeds + 1):
        mission = Mission(base.model_copy(update={"seed": seed}), resources)
        heard_max = 0.0
        while not mission.done:
            mission.step()
            where = dict(zip(mission.robot_ids, mission.bodies.true_xy(), strict=True))
            for robot, (x, y) in where.items():
                poses = mission.executors[robot].team_view.poses
                for mate, pose in poses.items():
                    if mate in where:  # a robot's, not the assigner's
                        heard_max = max(heard_max, math.hypot(pose.x - x, pose.y - y))
        # The true one is the run's own metric, as the link recorder keeps it.
        true_maxima.append(float(mission.link_recorder.max_separation.max()))
        heard_maxima.append(heard_max)
    return statistics.mean(true_maxima), statistics.mean(heard_maxima)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--behaviour", default="lf", choices=("lf", "nb"))
    parser.add_argument("--network", default="ah", choices=("ah", "wlan"))
    parser.add_argument("--seeds", type=int, default=6, help="missions per loss level")
    args = parser.parse_args()
    print(f"{args.behaviour.upper()} · {args.network.upper()} · SLT, {args.seeds} missions each")
    for spl in SPLS:
        true_max, heard_max = separations(args.behaviour, args.network, spl, args.seeds)
        print(f"  SPL {spl:g}: maximum separation {true_max:.2f} m, as heard {heard_max:.2f} m")


if __name__ == "__main__":
    main()
