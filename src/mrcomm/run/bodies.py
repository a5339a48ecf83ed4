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


class RobotBodies:
    """Every robot's :class:`SimBase`, in scenario order."""

    def __init__(self, bases: dict[str, SimBase], assigner: AssignerSpec) -> None:
        self.bases = bases
        self.assigner = assigner
        self._next_sample = 0.0
        self._radii = [b.neighbour_radius for b in bases.values()]

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
        within its neighbour radius (found with a grid of cells): the others cannot
        matter to it this step, so the outcome is the same at O(N) instead of O(N²)."""
        bases = list(self.bases.values())
        if len(bases) <= SMALL_TEAM:
            for i, base in enumerate(bases):
                base.update(dt, now, truth[:i] + truth[i + 1 :])
            return
        for i, near in enumerate(neighbours(truth, self._radii)):
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
