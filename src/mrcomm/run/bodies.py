"""The robots' simulated bodies, stepped together: what the simulation and the live
world process both run under the agents.

Each step every body advances seeing the others' true positions from before the step;
positions for the link model include the task assigner's (hosted, base station or
virtual); trajectories are sampled every :data:`TRAJECTORY_PERIOD`; at the end each
body's ground truth (odometry distance, separations, re-plans, recoveries) goes into
the run's facts.
"""

from __future__ import annotations

from mrcomm.net.links import LinkRecorder
from mrcomm.robot.base import SimBase
from mrcomm.run.assemble import RobotTruth
from mrcomm.world.scenario import AssignerSpec
from mrcomm.world.spatial import neighbours

TRAJECTORY_PERIOD = 0.5  # simulated s between recorded trajectory samples
#: Teams up to this size hand every body all the others (as cheap as finding the near
#: ones); larger teams only the mates within each body's neighbour radius.
SMALL_TEAM = 8

Point = tuple[float, float]
#: Bodies are handed the mates found within their neighbour radius plus this (m), and
#: the search is made again only once a body has moved half of it: until then a mate
#: within the radius now was within the radius plus SKIN then (two bodies closed in at
#: most SKIN). A body tests the distance to each mate it is handed itself, so the extra
#: mates change nothing.
SKIN = 1.0


def moved_farther(before: list[Point], now: list[Point], distance: float) -> bool:
    """Whether any point moved farther than ``distance`` from ``before`` to ``now``."""
    d2 = distance * distance
    return any(
        (x - x0) * (x - x0) + (y - y0) * (y - y0) > d2
        for (x0, y0), (x, y) in zip(before, now, strict=True)
    )


class RobotBodies:
    """Every robot's :class:`SimBase`, in scenario order."""

    def __init__(self, bases: dict[str, SimBase], assigner: AssignerSpec) -> None:
        self.bases = bases
        self.assigner = assigner
        self._next_sample = 0.0
        # Each body's mates within its neighbour radius plus SKIN, found where the bodies
        # stood at ``_found_at``: kept while no body has moved SKIN / 2 since.
        self._radii = [b.neighbour_radius + SKIN for b in bases.values()]
        self._near: list[list[int]] = []
        self._found_at: list[Point] = []
        #: How many times the mates near each body were searched for.
        self.searches = 0

    def true_xy(self) -> list[Point]:
        return [b.true_xy for b in self.bases.values()]

    def node_positions(self, robots: list[Point]) -> list[Point]:
        """The robots' positions followed by the task assigner's (plain tuples: the link
        model works on them directly, no array round trip)."""
        assigner = self.assigner.locate(dict(zip(self.bases, robots, strict=True)))
        return [*robots, assigner]

    def advance(self, dt: float, now: float, truth: list[Point]) -> None:
        """Advance every body by ``dt``; ``truth`` holds the positions before the step,
        each body's view of the others. In a large team a body is given only the mates
        within its neighbour radius (found with a grid of cells, again only once a body
        has moved ``SKIN / 2``) and a few more: the others cannot matter to it this step,
        so the outcome is the same at O(N) instead of O(N²)."""
        bases = list(self.bases.values())
        if len(bases) <= SMALL_TEAM:
            for i, base in enumerate(bases):
                base.update(dt, now, truth[:i] + truth[i + 1 :])
            return
        if not self._found_at or moved_farther(self._found_at, truth, SKIN / 2):
            self._near = neighbours(truth, self._radii)
            self._found_at = truth
            self.searches += 1
        for i, near in enumerate(self._near):
            bases[i].update(dt, now, [truth[j] for j in near], near)

    def sample_due(self, now: float) -> bool:
        """Whether a trajectory sample is due at ``now`` (then the next one is booked)."""
        if now >= self._next_sample:
            self._next_sample += TRAJECTORY_PERIOD
            return True
        return False

    def sample(self) -> dict[str, tuple[float, float]]:
        """Each robot's true position, rounded to the millimetre, for a trajectory."""
        out = {}
        for rid, base in self.bases.items():
            p = base.true_pose
            out[rid] = (round(p.x, 3), round(p.y, 3))
        return out

    def truth(self, recorder: LinkRecorder) -> dict[str, RobotTruth]:
        """Each robot's ground truth at the end of the run."""
        out: dict[str, RobotTruth] = {}
        separations = recorder.separations()
        for i, (rid, base) in enumerate(self.bases.items()):
            closest, furthest = separations[i]
            out[rid] = RobotTruth(
                distance=round(base.odometry_distance, 6),
                min_separation=closest,
                max_separation=furthest,
                replans=base.replans,
                recoveries=base.recoveries,
            )
        return out
