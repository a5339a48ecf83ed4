"""SimBase: the simulated implementation of the Base port (ports.py) — one robot's
body and navigation stack, advanced by the simulator with :meth:`SimBase.update`.

Per step it: follows the planned path (follower.py), re-plans around team mates that
block the path ahead (rate-limited; waits when there is no way round), detects being
stuck and recovers (stop, clear the plan, reverse by odometry, re-plan, resume), and
integrates the motion under the speed and acceleration limits. A motion that would put
the footprint into a wall of the true map, or closer than two radii (plus one step of
travel) to a team mate, is refused: the robot stops instead of colliding.

Ground truth (``true_pose``) feeds the world, the network model and recordings; agents
see only the localisation estimate (``pose``), the noisy odometer and ``status``.
Under the ``realistic`` variation profile (robot/variation.py) a base has its own top
speed, start-up delay, AMCL-like localisation error and its run's planner costs; with
none (the default) it is the robot of earlier versions, draw for draw.
The steady-state step is scalar Python on floats: no numpy calls, no arrays.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from mrcomm.ports import NavStatus
from mrcomm.robot.follower import PathFollower
from mrcomm.robot.kinematics import integrate, limit_velocity, wrap
from mrcomm.robot.noise import AmclError, LocalisationError, NormalStream, Odometry
from mrcomm.robot.params import RobotParams
from mrcomm.robot.planner import GridPlanner, PlanMemo, PlannedPath
from mrcomm.robot.repair import repaired_route
from mrcomm.robot.variation import RobotVariation
from mrcomm.world.geometry import Pose
from mrcomm.world.occupancy import OccupancyGrid

Point = tuple[float, float]

_IDLE, _FOLLOW, _REVERSE = 0, 1, 2
#: The speed (m/s) at which any mate is assumed at most to drive when bounding which
#: mates can matter (:attr:`SimBase.neighbour_radius`; robots' max_v is 0.5 by default).
NEIGHBOUR_MAX_SPEED = 1.0
#: Localisation error (m) allowed for in that bound (the simulated error is centimetres).
NEIGHBOUR_LOCALISATION = 0.5


class SimBase:
    """A simulated differential-drive robot with move_base-like navigation."""

    def __init__(
        self,
        robot_id: str,
        grid: OccupancyGrid,
        planner: GridPlanner,
        start: Pose,
        params: RobotParams,
        rng: np.random.Generator,
        variation: RobotVariation | None = None,
    ) -> None:
        """``variation``: this robot's share of the run's variation (robot/variation.py;
        None: the deterministic robot of earlier versions, unchanged)."""
        if planner.grid is not grid:
            raise ValueError("planner was built for a different grid")
        self.robot_id = robot_id
        self.grid = grid
        self.planner = planner
        # A mate may be as fast as the fastest robot the profile allows (contact check).
        self._mate_v = params.max_v
        self._ready_at = -math.inf  # no start-up delay
        self._speed_factor = 1.0
        self._weights = None if variation is None else variation.weights
        self._plan_memo = PlanMemo()  # its last search without mates (planner.PlanMemo)
        if variation is not None:
            factor = self._speed_factor = variation.draws.speed_factor
            self._mate_v = params.max_v * max(1.0, variation.params.speed_max)
            self._ready_at = variation.draws.start_delay
            # This robot's own limits: the follower and the kinematics both read max_v.
            params = dataclasses.replace(params, max_v=params.max_v * factor)
        self.params = params
        self._x, self._y, self._th = float(start.x), float(start.y), wrap(float(start.theta))
        #: The localisation estimate as last built (None: to build): it changes only
        #: when the robot moves or is carried, and is read several times a step.
        self._pose: Pose | None = None
        self._v = 0.0
        self._w = 0.0
        normals = NormalStream(rng)
        self._odo = Odometry(
            normals,
            (self._x, self._y, self._th),
            params.odom_distance_noise,
            params.odom_heading_noise,
        )
        self._loc: LocalisationError
        if variation is None:
            self._loc = LocalisationError(
                normals,
                params.loc_position_noise,
                params.loc_heading_noise,
                params.loc_noise_time_constant,
            )
        else:
            v = variation.params
            self._loc = AmclError(
                normals,
                v.loc_position_sigma,
                v.loc_heading_sigma,
                v.loc_time_constant,
                variation.loc_rng,
                drift_sigma=v.heading_drift_sigma,
                drift_tau=v.heading_drift_time_constant,
                jump_rate=v.jump_rate,
                jump_sigma=v.jump_sigma,
                jump_heading_sigma=v.jump_heading_sigma,
            )
        self._status = NavStatus.IDLE
        self._mode = _IDLE
        self._goal: Point | None = None  # as requested
        self._target: Point | None = None  # as planned (snapped out of the inflated zone)
        self._follower: PathFollower | None = None
        # The route cancel() gave up, with the goal it was for: asked for the same goal
        # again (resuming after giving way), a base with a repair horizon repairs it.
        self._left: tuple[Point, PathFollower] | None = None
        self._now = 0.0
        # Stuck detection: where and when the robot last made progress.
        self._anchor_x = 0.0
        self._anchor_y = 0.0
        self._anchor_t: float | None = None
        self._last_replan = -math.inf
        self._in_row = 0  # recoveries for this goal without progress in between
        self._progress_mark = 0.0  # odometer reading when the last recovery ended
        self._rev_target = 0.0
        self._rev_done = 0.0
        self._rev_deadline = 0.0
        self._rev_blocked = False
        self._waiting = False
        self._prev_others: dict[int, Point] = {}  # mate -> its position at the last check
        self._prev_t = -math.inf
        self._goal_taken = False  # holding in front of a mate that stands on our goal
        # Thresholds used every step (squared where compared with squared distances).
        self._sense2 = params.sensing_range**2
        self._block = 2 * params.radius + params.block_margin
        self._hold2 = params.hold_distance**2
        self.replans = 0  #: re-plans after the first plan of a goal (mates, recoveries)
        self.recoveries = 0  #: stuck recoveries started
        self.bumps = 0  #: steps whose translation was refused (wall or mate in the way)

    @property
    def neighbour_radius(self) -> float:
        """Within this distance of its true position (m) a mate can matter to this
        robot this step: seen within the sensing range from its localised pose, in
        contact, in the way of backing off. It adds the distance two robots close in
        0.5 s (mates' motion is judged over at most that long) and a localisation
        error, both at :data:`NEIGHBOUR_MAX_SPEED`."""
        p = self.params
        reach = max(p.sensing_range, p.reverse_distance + 2 * p.radius + 0.05)
        return reach + 2 * 0.5 * max(p.max_v, NEIGHBOUR_MAX_SPEED) + NEIGHBOUR_LOCALISATION

    # ------------------------------------------------------------ Base port
    def navigate_to(self, x: float, y: float) -> None:
        """Plan to (x, y) from the current estimate and start following (replaces any
        current goal). No path -> status ABORTED at once."""
        goal = (float(x), float(y))
        route = self._follower if self._goal == goal else None
        if route is None and self._left is not None and self._left[0] == goal:
            route = self._left[1]
        self._left = None
        self._goal = self._target = goal
        self._in_row = 0
        self._progress_mark = self._odo.distance
        self._anchor_t = None
        path = self._replan((), route)
        if path is None:
            self._abort()
            return
        self._follow(path)

    def cancel(self) -> None:
        """Drop the goal; the robot brakes to a stop within its acceleration limits."""
        if self._goal is not None and self._follower is not None:
            self._left = (self._goal, self._follower)
        self._goal = self._target = None
        self._follower = None
        self._mode = _IDLE
        self._waiting = False
        self._status = NavStatus.IDLE

    @property
    def status(self) -> NavStatus:
        return self._status

    @property
    def pose(self) -> Pose:
        """Localisation estimate (true pose plus a small, slowly varying error)."""
        pose = self._pose
        if pose is None:
            loc = self._loc
            pose = self._pose = Pose(self._x + loc.ex, self._y + loc.ey, wrap(self._th + loc.eth))
        return pose

    @property
    def odometry_distance(self) -> float:
        return self._odo.distance

    @property
    def speed(self) -> float:
        """Signed forward speed (m/s; negative while reversing)."""
        return self._v

    # ----------------------------------------------------- simulator side
    def carry(self, x: float, y: float) -> None:
        """Pick the robot up and set it down at rest at (x, y) — a kidnapped robot, as
        tests of regrouping need. Its localisation follows at once (as after an AMCL
        re-localisation); its odometer does not count the trip; a goal it was driving
        to is planned again from there."""
        self._x, self._y = float(x), float(y)
        self._pose = None
        self._v = self._w = 0.0
        if self._goal is not None and self._status is NavStatus.ACTIVE:
            self.navigate_to(*self._goal)

    @property
    def true_pose(self) -> Pose:
        return Pose(self._x, self._y, self._th)

    @property
    def true_xy(self) -> Point:
        """True position (x, y): the cheapest accessor for the simulator's per-step use."""
        return self._x, self._y

    @property
    def angular_speed(self) -> float:
        return self._w

    @property
    def odometry_pose(self) -> Pose:
        """Dead-reckoned pose from wheel odometry alone (drifts)."""
        o = self._odo
        return Pose(o.x, o.y, wrap(o.theta))

    @property
    def goal(self) -> Point | None:
        """The goal being driven to (after snapping out of the inflated zone)."""
        return self._target

    @property
    def path(self) -> tuple[Point, ...]:
        """Waypoints of the current plan (empty when not following one)."""
        return self._follower.waypoints if self._follower is not None else ()

    @property
    def route(self) -> tuple[Point, ...]:
        """Base port: the waypoints of the current plan still ahead (empty when not
        following one)."""
        return self._follower.remaining if self._follower is not None else ()

    @property
    def waiting(self) -> bool:
        """True while holding for a team mate that blocks the path with no way round."""
        return self._waiting

    @property
    def recovering(self) -> bool:
        return self._mode == _REVERSE

    @property
    def start_delay(self) -> float:
        """Simulated s before this robot first moves (0 without variation)."""
        return max(self._ready_at, 0.0)

    @property
    def speed_factor(self) -> float:
        """This robot's top speed over the nominal one (1 without variation)."""
        return self._speed_factor

    @property
    def localisation_jumps(self) -> int:
        """Re-localisation jumps so far (always 0 without variation)."""
        return getattr(self._loc, "jumps", 0)

    def update(
        self,
        dt: float,
        now: float,
        others: Sequence[Point] = (),
        mates: Sequence[int] | None = None,
    ) -> None:
        """Advance the robot by ``dt`` seconds; ``others`` are the true (x, y) of the
        other robots (used for sensing within range and for contact): all of them, or
        at least those within :attr:`neighbour_radius`; ``mates`` identifies each of
        ``others`` from step to step (default: its place in ``others``)."""
        self._now = now
        if now < self._ready_at:
            return  # still starting up (variation's start delay): a goal waits
        mode = self._mode
        if mode == _FOLLOW:
            ids = range(len(others)) if mates is None else mates
            v_cmd, w_cmd = self._follow_step(now, others, ids)
        elif mode == _REVERSE:
            v_cmd, w_cmd = self._reverse_step(now, others)
        else:
            if self._v == 0.0 and self._w == 0.0:
                return
            v_cmd = w_cmd = 0.0
        self._move(v_cmd, w_cmd, dt, others)

    # ------------------------------------------------------------- motion
    def _move(self, v_cmd: float, w_cmd: float, dt: float, others: Sequence[Point]) -> None:
        p = self.params
        v, w = limit_velocity(
            v_cmd, w_cmd, self._v, self._w, dt, p.max_v, p.max_w, p.max_accel, p.max_ang_accel
        )
        x, y, th = self._x, self._y, self._th
        nx, ny, nth = integrate(x, y, th, v, w, dt)
        if v != 0.0 and self._refused(x, y, nx, ny, dt, others):
            nx, ny, nth = x, y, th + w * dt
            v = 0.0
            self.bumps += 1
            if self._mode == _REVERSE:
                self._rev_blocked = True
        dth = nth - th
        if nth > math.pi or nth < -math.pi:
            nth = wrap(nth)  # keep the true heading in [-pi, pi)
        self._x, self._y, self._th = nx, ny, nth
        self._pose = None
        self._v, self._w = v, w
        if v != 0.0 or w != 0.0:
            ds = v * dt
            step = self._odo.add(ds, dth)
            if ds < 0.0:
                self._rev_done += step
            self._loc.step(dt)

    def _refused(
        self, x: float, y: float, nx: float, ny: float, dt: float, others: Sequence[Point]
    ) -> bool:
        """Would moving from (x, y) to (nx, ny) hit a wall or a team mate? Moving away
        from something already too close is allowed, so the robot can always escape."""
        p = self.params
        clear = self.planner.clearance
        c_new = clear(nx, ny)
        if c_new < p.radius and c_new < clear(x, y):
            return True
        # A mate may move up to its max_v*dt this step too (the simulator may hand us
        # positions from before its move): keep that much extra distance.
        contact = 2 * p.radius + self._mate_v * dt
        contact2 = contact * contact
        for ox, oy in others:
            d2 = (nx - ox) ** 2 + (ny - oy) ** 2
            if d2 < contact2 and d2 < (x - ox) ** 2 + (y - oy) ** 2:
                return True
        return False

    # --------------------------------------------------------- navigation
    def make_plan(self, x: float, y: float) -> tuple[Point, ...] | None:
        """Base port: the route to (x, y) from the localised pose, without moving.
        Searched through the robot's memo: an agent that looks at a route and then
        drives it (LF's direct hop, the passage queue) does not search twice."""
        loc = self._loc
        path = self.planner.plan(
            (self._x + loc.ex, self._y + loc.ey),
            (float(x), float(y)),
            weights=self._weights,
            memo=self._plan_memo,
        )
        return None if path is None else path.waypoints

    def _plan(self, obstacles: Sequence[Point]) -> PlannedPath | None:
        assert self._goal is not None
        loc = self._loc
        start = (self._x + loc.ex, self._y + loc.ey)
        return self.planner.plan(
            start, self._goal, obstacles, weights=self._weights, memo=self._plan_memo
        )

    def _replan(self, obstacles: Sequence[Point], route: PathFollower | None) -> PlannedPath | None:
        """The way to the goal round ``obstacles``: ``route`` repaired when the params
        give a repair horizon (robot/repair.py), else (or when the repair finds no way)
        the whole route searched again."""
        horizon = self.params.repair_horizon
        if horizon > 0.0 and route is not None:
            loc = self._loc
            start = (self._x + loc.ex, self._y + loc.ey)
            path = repaired_route(
                self.planner, start, route, horizon, obstacles, self._weights, self._plan_memo
            )
            if path is not None:
                return path
        return self._plan(obstacles)

    def _follow(self, path: PlannedPath) -> None:
        self._target = path.goal
        self._follower = PathFollower(path.waypoints, self.params)
        self._mode = _FOLLOW
        self._status = NavStatus.ACTIVE

    def _abort(self) -> None:
        self._follower = None
        self._mode = _IDLE
        self._waiting = False
        self._status = NavStatus.ABORTED

    def _mates_in_range(self, ex: float, ey: float, others: Sequence[Point]) -> list[Point]:
        s2 = self._sense2
        return [(ox, oy) for ox, oy in others if (ox - ex) ** 2 + (oy - ey) ** 2 <= s2]

    def _follow_step(
        self, now: float, others: Sequence[Point], mates: Sequence[int]
    ) -> tuple[float, float]:
        p = self.params
        loc = self._loc
        ex = self._x + loc.ex
        ey = self._y + loc.ey
        # Stuck detection on the estimate (it only changes while the robot moves). Not
        # while a mate stands on our goal: waiting for it is the only sensible thing.
        if (
            self._goal_taken
            or self._anchor_t is None
            or math.hypot(ex - self._anchor_x, ey - self._anchor_y) > p.stuck_distance
        ):
            self._anchor_x, self._anchor_y, self._anchor_t = ex, ey, now
        elif now - self._anchor_t >= p.stuck_timeout:
            return self._start_recovery(now, others)
        if self._in_row and self._odo.distance - self._progress_mark >= p.progress_reset:
            self._in_row = 0
        follower = self._follower
        assert follower is not None
        hold = False
        self._goal_taken = False
        if others:
            hold = self._check_mates(ex, ey, now, others, mates)
            follower = self._follower
            assert follower is not None
        self._waiting = hold
        cmd = follower.command(ex, ey, self._th + loc.eth)
        if cmd is None:
            self._follower = None
            self._mode = _IDLE
            self._waiting = False
            self._status = NavStatus.SUCCEEDED
            return 0.0, 0.0
        if hold:
            return 0.0, 0.0
        return cmd

    def _check_mates(
        self, ex: float, ey: float, now: float, others: Sequence[Point], mates: Sequence[int]
    ) -> bool:
        """Re-plan around mates blocking the path ahead; True when we must hold.

        A mate standing on the goal itself cannot be planned around: we hold in front
        of it, without re-planning or stuck recovery, until it leaves. A blocking mate
        that is driving away from us (judged from its position at the last check, up to
        0.5 s ago) is clearing the way by itself: we may hold behind it, but we do not
        re-plan around it.
        """
        p = self.params
        follower = self._follower
        assert follower is not None
        s2 = self._sense2
        prev = self._prev_others
        gap = now - self._prev_t
        recent = 0.0 < gap <= 0.5
        gx, gy = follower.goal
        block2 = self._block * self._block
        blocking: list[Point] = []
        on_goal: list[Point] = []
        static = False
        for k, (ox, oy) in enumerate(others):
            d2 = (ox - ex) ** 2 + (oy - ey) ** 2
            if d2 > s2:
                continue
            if follower.clearance_ahead(ox, oy, ex, ey, p.sensing_range) < self._block:
                blocking.append((ox, oy))
                if (ox - gx) ** 2 + (oy - gy) ** 2 < block2:
                    on_goal.append((ox, oy))
                    continue
                last = prev.get(mates[k]) if recent else None
                if last is None:
                    continue  # first sighting: judge its motion on the next step
                if d2 > 0.0:
                    px, py = last
                    away = ((ox - px) * (ox - ex) + (oy - py) * (oy - ey)) / (gap * math.sqrt(d2))
                    if away > 0.1:  # m/s away from us
                        continue
                static = True
        self._prev_others = dict(zip(mates, others, strict=True))
        self._prev_t = now
        if not blocking:
            return False
        if static and now - self._last_replan >= p.replan_interval:
            self._last_replan = now
            self.replans += 1
            path = self._replan(self._mates_in_range(ex, ey, others), follower)
            limit = p.max_detour_ratio * follower.remaining_length(ex, ey) + 1.0
            if path is not None and path.length <= limit:
                self._follow(path)
                return False
        hold2 = self._hold2
        self._goal_taken = any((ox - ex) ** 2 + (oy - ey) ** 2 < hold2 for ox, oy in on_goal)
        return self._goal_taken or any(
            (ox - ex) ** 2 + (oy - ey) ** 2 < hold2 for ox, oy in blocking
        )

    # ----------------------------------------------------- stuck recovery
    def _start_recovery(self, now: float, others: Sequence[Point]) -> tuple[float, float]:
        """Stuck: stop, clear the plan, and back off (if there is room behind)."""
        self.recoveries += 1
        self._in_row += 1
        self._follower = None
        self._waiting = False
        if self._in_row > self.params.max_recoveries:
            self._abort()
            return 0.0, 0.0
        p = self.params
        self._mode = _REVERSE
        self._rev_target = self._free_behind(others)
        self._rev_done = 0.0
        self._rev_blocked = False
        # Stop first (accel limit), then reverse; give up if it takes far too long.
        self._rev_deadline = (
            now + self._rev_target / p.reverse_speed + 2.0 * p.max_v / p.max_accel + 1.0
        )
        return 0.0, 0.0

    def _free_behind(self, others: Sequence[Point]) -> float:
        """How far (up to the reverse distance) the robot can back straight up."""
        p = self.params
        c, s = math.cos(self._th), math.sin(self._th)
        contact2 = (2 * p.radius + 0.05) ** 2
        free = 0.0
        d = 0.05
        while d <= p.reverse_distance + 1e-9:
            bx, by = self._x - d * c, self._y - d * s
            if self.planner.clearance(bx, by) < p.radius + 0.02:
                break
            if any((bx - ox) ** 2 + (by - oy) ** 2 < contact2 for ox, oy in others):
                break
            free = d
            d += 0.05
        return free

    def _reverse_step(self, now: float, others: Sequence[Point]) -> tuple[float, float]:
        p = self.params
        if self._rev_done < self._rev_target and not self._rev_blocked and now < self._rev_deadline:
            return -p.reverse_speed, 0.0
        if self._v > 0.0 or self._v < 0.0:
            return 0.0, 0.0  # come to a stop before planning again
        # Resume the same goal: plan around mates in range, else plainly, else give up.
        self.replans += 1
        loc = self._loc
        mates = self._mates_in_range(self._x + loc.ex, self._y + loc.ey, others)
        path = self._plan(mates) if mates else None
        if path is None:
            path = self._plan(())
        if path is None:
            self._abort()
            return 0.0, 0.0
        self._follow(path)
        self._anchor_t = None
        self._progress_mark = self._odo.distance
        return 0.0, 0.0
