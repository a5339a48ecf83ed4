"""The simulated bodies stepped together: each is handed at least every mate within its
neighbour radius, at every step, though the mates near each are searched for again only
once a body has moved far enough."""

from __future__ import annotations

import math
import random

from mrcomm.run.bodies import SKIN, SMALL_TEAM, RobotBodies
from mrcomm.world.scenario import AssignerSpec


class Body:
    """Stands in for a SimBase: records the mates it is handed."""

    neighbour_radius = 3.0

    def __init__(self) -> None:
        self.handed: list[tuple[list[tuple[float, float]], list[int]]] = []

    def update(self, dt, now, others, mates=None) -> None:
        self.handed.append((list(others), list(mates)))


def test_every_body_is_handed_every_mate_within_its_radius_and_searches_are_few() -> None:
    rng = random.Random(5)
    n = SMALL_TEAM + 12
    bodies = {f"robot_{i}": Body() for i in range(n)}
    team = RobotBodies(bodies, AssignerSpec("virtual"))  # type: ignore[arg-type]
    points = [(rng.uniform(0, 20), rng.uniform(0, 20)) for _ in range(n)]
    steps = 400
    for step in range(steps):
        if step == 200:
            points[3] = (points[3][0] + 6.0, points[3][1])  # a body carried away
        truth = list(points)
        team.advance(0.1, step * 0.1, truth)
        for i, body in enumerate(bodies.values()):
            others, mates = body.handed[-1]
            assert i not in mates
            assert others == [truth[j] for j in mates]
            within = [j for j in range(n) if j != i and math.dist(truth[i], truth[j]) <= 3.0]
            assert set(within) <= set(mates), (step, i)
        # every body drives up to 0.05 m a step (0.5 m/s)
        points = [(x + rng.uniform(-0.05, 0.05), y + rng.uniform(-0.05, 0.05)) for x, y in points]
    assert steps / 40 < team.searches < steps / 5
    before = team.searches
    team.advance(0.1, steps * 0.1, [(x + SKIN, y) for x, y in points])  # all moved SKIN
    assert team.searches == before + 1
