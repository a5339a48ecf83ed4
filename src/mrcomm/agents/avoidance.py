"""Collision avoidance between team mates, as one part of an executor: which mate's
pose puts it in the robot's danger zone, who has right of way, when the robot may move
on, and the growing grace that breaks livelocks.

The rules, beyond right of way (collision.py):

* **Grace.** Moving on from a conflict starts a grace with that mate: no new conflict
  with it for ``resume_grace`` s. The grace doubles (up to ``max_grace``) with each
  *repeat*, a conflict with the same mate within ``repeat_window`` s of the last one:
  pausing again and again for the same mate means the bases are jammed, so navigation's
  re-planning and stuck recovery get longer each time before the next pause.
* **Knots** (teams of more than two meeting at a door or in a corridor). A robot can
  pause in turn for two or more mates, each pause starting right after it moved on from
  the last, so no mate repeats within its window and the grace never grows. So pauses
  are also counted per robot, whoever the mate: a pause that starts within
  ``repeat_window`` s of moving on extends the robot's run of pauses in a row. A robot
  that has paused more than ``knot_pauses`` times in a row is in a knot: its grace
  doubles for each pause beyond that, whichever mate the pause was for, until the
  graces overlap and the bases, re-planning around each other, untangle the knot.
  Encounters of two or three robots end within a few pauses and are left as they were:
  the longest run in the 3-robot S1 reference runs (tests/golden) is 4, the default.
* **No news, no second pause.** A mate's pose that the robot has already moved on from
  (the same message: nothing newer heard from the mate since) cannot stop it again:
  a mate last heard long ago, then out of range, would otherwise stop the robot every
  time the grace runs out while it passes the place where the mate was.
* **When a pose is judged** (``judge_poses``). By default every step, from each
  mate's last received pose: a mate whose poses are lost is still avoided where it was
  last heard. With ``on_receipt`` each pose is judged once, at the first step after it
  arrived, whatever the robot is doing then (paused, in a grace): the original robots
  checked a mate "whenever a task execution agent receives a team member's updated
  position" (their pose callback), so a lost pose is no check at all and fewer near
  collisions are judged as loss grows, as the original reports.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from mrcomm.agents.collision import Mate, classify, has_right_of_way
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.world.geometry import Pose


@dataclass(frozen=True)
class Conflict:
    """A near collision found this step."""

    mate: str
    kind: str
    #: Another one with the same mate within the repeat window.
    repeat: bool


class Avoidance:
    """The near-collision state of one robot."""

    def __init__(self, robot: str, params: ExecutorParams, rank: Callable[[str], float]) -> None:
        self.robot = robot
        self.params = params
        self._rank = rank
        self.mate: str | None = None  # the mate of the current conflict
        self.right_of_way = False
        self._clear_since: float | None = None
        self._grace_until: dict[str, float] = {}
        self._last_conflict: dict[str, float] = {}
        self._repeats: dict[str, int] = {}
        #: mate -> the stamp of the pose the robot last moved on from.
        self._passed: dict[str, float] = {}
        self._last_resume = -float("inf")
        #: judge_poses "on_receipt": mate -> the stamp of the last pose judged.
        self._judged: dict[str, float] | None = {} if params.judge_poses == "on_receipt" else None
        #: Pauses in a row, whoever the mate, each soon after moving on (1: the first).
        self.pauses_in_row = 0

    @property
    def on_receipt(self) -> bool:
        """Whether each mate's pose is judged once, when it arrives (give every mate)."""
        return self._judged is not None

    @property
    def reach(self) -> float:
        """Beyond this distance along either axis a mate cannot be in conflict."""
        collision = self.params.collision
        return max(collision.danger_radius, collision.event_horizon)

    def detect(
        self,
        pose: Pose,
        mates: Iterable[Mate],
        now: float,
        goal_distance: Callable[[], float],
    ) -> Conflict | None:
        """The first mate in conflict with ``pose`` (outside its grace, and not a pose
        already moved on from), which becomes the current conflict with right of way
        decided; None when there is none."""
        collision = self.params.collision
        # Beyond reach along either axis no mate can be in conflict (classify would say
        # so): skipped without a call, which matters when the team is large.
        # (Chained comparisons rather than abs(): the same test without a call per mate.)
        reach = self.reach
        short = -reach
        x, y = pose.x, pose.y
        judged = self._judged
        for mate in mates:
            if judged is not None:
                if judged.get(mate.robot) == mate.stamp:
                    continue  # judged when it arrived: no news since
                judged[mate.robot] = mate.stamp
            if not (short <= mate.x - x <= reach and short <= mate.y - y <= reach):
                continue
            if self._grace_until.get(mate.robot, -1.0) > now:
                continue
            if self._passed.get(mate.robot) == mate.stamp:
                continue  # no news from it since the robot moved on from this pose
            kind = classify(pose, mate, collision)
            if kind is None:
                continue
            window = self.params.repeat_window
            previous = self._last_conflict.get(mate.robot)
            repeat = previous is not None and now - previous < window
            self._last_conflict[mate.robot] = now
            self._repeats[mate.robot] = self._repeats.get(mate.robot, 0) + 1 if repeat else 0
            in_row = now - self._last_resume < window
            self.pauses_in_row = self.pauses_in_row + 1 if in_row else 1
            self.mate = mate.robot
            self._clear_since = None
            self.right_of_way = has_right_of_way(
                goal_distance(), mate.goal_dist, self._rank(self.robot), self._rank(mate.robot)
            )
            return Conflict(mate.robot, kind, repeat)
        return None

    def grace(self) -> float:
        """The grace given to the current mate when the robot moves on: doubled for each
        repeat with that mate, or for each pause in a row beyond ``knot_pauses``."""
        params = self.params
        doublings = max(
            self._repeats.get(self.mate or "", 0), self.pauses_in_row - params.knot_pauses
        )
        return min(params.resume_grace * 2**doublings, params.max_grace)

    def may_resume(
        self, pose: Callable[[], Pose], mates: Mapping[str, Mate], now: float, since: float
    ) -> bool:
        """Whether a robot paused since ``since`` may move on: after the pause, at once
        with right of way; without it once the mate has been clear for a while, or after
        the give-way time-out. Resuming starts the mate's grace."""
        elapsed = now - since
        params = self.params
        if elapsed < params.collision_pause:
            return False
        if not self.right_of_way and elapsed < params.give_way_timeout:
            mate = mates.get(self.mate or "")
            in_conflict = mate is not None and classify(pose(), mate, params.collision) is not None
            if in_conflict:
                self._clear_since = None
                return False
            if self._clear_since is None:
                self._clear_since = now
            if now - self._clear_since < params.clear_time:
                return False
        self._last_resume = now
        if self.mate is not None:
            self._grace_until[self.mate] = now + self.grace()
            passed = mates.get(self.mate)
            if passed is not None:
                self._passed[self.mate] = passed.stamp
        return True
