"""Local path following: a carrot (pure-pursuit style) controller for a polyline path.

The carrot is ``params.lookahead`` ahead of the robot's projection on the path, but it
never runs past a *corner* (a waypoint turning more than ``params.corner_angle``) or the
goal: the robot drives up to a corner, slows down, turns (in place when the heading
error is large) and carries on. Mild bends are taken smoothly. This keeps the robot
within a few centimetres of the planned polyline, whose clearance the planner chose.

Also answers the geometric questions the base asks about the path ahead: how much of
it is left, and how close a team mate stands to the next stretch of it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from mrcomm.robot.params import RobotParams

Point = tuple[float, float]


class PathFollower:
    """Follows one planned path; :meth:`command` is called once per simulation step."""

    __slots__ = (
        "_a_brake",
        "_corner",
        "_last",
        "_p",
        "_pts",
        "_seglen",
        "_to_corner",
        "seg",
    )

    def __init__(self, waypoints: Sequence[Point], params: RobotParams) -> None:
        pts = [(float(x), float(y)) for x, y in waypoints]
        if len(pts) < 2:
            pts = [pts[0], pts[0]]
        self._pts = pts
        self._p = params
        n = len(pts)
        self._last = n - 1
        self.seg = 1  # index of the waypoint we are heading for
        # seglen[k]: length of the segment ending at waypoint k.
        self._seglen = [0.0] + [
            math.hypot(pts[k][0] - pts[k - 1][0], pts[k][1] - pts[k - 1][1]) for k in range(1, n)
        ]
        corner = [True] * n
        for k in range(1, n - 1):
            h0 = math.atan2(pts[k][1] - pts[k - 1][1], pts[k][0] - pts[k - 1][0])
            h1 = math.atan2(pts[k + 1][1] - pts[k][1], pts[k + 1][0] - pts[k][0])
            turn = abs((h1 - h0 + math.pi) % math.tau - math.pi)
            corner[k] = turn > params.corner_angle or self._seglen[k] == 0.0
        self._corner = corner
        # to_corner[k]: path distance from waypoint k to the next corner at or after it.
        to_corner = [0.0] * n
        for k in range(n - 2, -1, -1):
            to_corner[k] = 0.0 if corner[k] else to_corner[k + 1] + self._seglen[k + 1]
        self._to_corner = to_corner
        # Brake at half the acceleration limit so the stop is gentle and never late.
        self._a_brake = 0.5 * params.max_accel

    @property
    def waypoints(self) -> tuple[Point, ...]:
        return tuple(self._pts)

    @property
    def remaining(self) -> tuple[Point, ...]:
        """The waypoints not yet reached, the goal last."""
        return tuple(self._pts[self.seg :])

    @property
    def goal(self) -> Point:
        return self._pts[-1]

    def command(self, x: float, y: float, theta: float) -> tuple[float, float] | None:
        """(v, w) wanted at pose (x, y, theta), or None once the goal is reached."""
        p = self._p
        pts = self._pts
        last = self._last
        seg = self.seg
        # Advance past waypoints we have reached or passed.
        t = 0.0
        while True:
            ax, ay = pts[seg - 1]
            bx, by = pts[seg]
            dx = bx - ax
            dy = by - ay
            l2 = dx * dx + dy * dy
            t = ((x - ax) * dx + (y - ay) * dy) / l2 if l2 > 0.0 else 1.0
            if seg == last:
                break
            switch = p.corner_switch if self._corner[seg] else p.lookahead
            if t >= 1.0 or math.hypot(bx - x, by - y) < switch:
                seg += 1
                continue
            break
        self.seg = seg
        gx, gy = pts[last]
        d_goal = math.hypot(gx - x, gy - y)
        if seg == last and d_goal < p.goal_tolerance:
            return None
        # Carrot: lookahead along the path from our projection, stopped at a corner.
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
        seg_len = self._seglen[seg]
        remaining = (1.0 - t) * seg_len
        look = p.lookahead
        if remaining >= look and seg_len > 0.0:
            f = t + look / seg_len
            cx = ax + f * dx
            cy = ay + f * dy
        elif self._corner[seg] or seg == last:
            cx, cy = bx, by
        else:
            nx, ny = pts[seg + 1]
            nlen = self._seglen[seg + 1]
            f = min(1.0, (look - remaining) / nlen) if nlen > 0.0 else 0.0
            cx = bx + f * (nx - bx)
            cy = by + f * (ny - by)
        err = (math.atan2(cy - y, cx - x) - theta + math.pi) % math.tau - math.pi
        w = p.heading_gain * err
        if abs(err) > p.rotate_threshold:
            return 0.0, w
        # Speed that still lets us stop (gently) at the next corner or at the goal.
        d_stop = math.hypot(bx - x, by - y) + self._to_corner[seg]
        v = math.sqrt(2.0 * self._a_brake * d_stop)
        if v < p.min_approach_speed:
            v = p.min_approach_speed
        if v > p.max_v:
            v = p.max_v
        return v * math.cos(err), w

    def remaining_length(self, x: float, y: float) -> float:
        """Path length from (x, y) (via the current target waypoint) to the goal."""
        pts = self._pts
        seg = self.seg
        bx, by = pts[seg]
        return math.hypot(bx - x, by - y) + sum(self._seglen[seg + 1 :])

    def ahead(self, x: float, y: float, distance: float) -> tuple[Point, list[Point]] | None:
        """The point ``distance`` m along the path from (x, y) (via the current target
        waypoint, as :meth:`remaining_length` measures) and the waypoints after it, to
        the goal; None when less than ``distance`` of the path is left."""
        pts = self._pts
        k = self.seg
        ax, ay = x, y
        left = distance
        while k <= self._last:
            bx, by = pts[k]
            length = math.hypot(bx - ax, by - ay)
            if length >= left:
                f = left / length if length > 0.0 else 0.0
                return (ax + f * (bx - ax), ay + f * (by - ay)), pts[k:]
            left -= length
            ax, ay = bx, by
            k += 1
        return None

    def clearance_ahead(self, ox: float, oy: float, x: float, y: float, horizon: float) -> float:
        """Distance from point (ox, oy) to the next ``horizon`` metres of path ahead of
        the robot at (x, y); ``inf`` when the point lies behind the robot."""
        pts = self._pts
        seg = self.seg
        # The stretch starts at the robot itself, heading for the current waypoint.
        ax, ay = x, y
        bx, by = pts[seg]
        hx, hy = bx - ax, by - ay
        if (ox - ax) * hx + (oy - ay) * hy <= 0.0 and (hx != 0.0 or hy != 0.0):
            return math.inf
        best = math.inf
        left = horizon
        k = seg
        while True:
            dx = bx - ax
            dy = by - ay
            length = math.hypot(dx, dy)
            if length > left:
                f = left / length
                bx, by = ax + f * dx, ay + f * dy
                dx, dy, length = bx - ax, by - ay, left
            l2 = dx * dx + dy * dy
            t = ((ox - ax) * dx + (oy - ay) * dy) / l2 if l2 > 0.0 else 0.0
            t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
            d = math.hypot(ax + t * dx - ox, ay + t * dy - oy)
            if d < best:
                best = d
            left -= length
            k += 1
            if left <= 0.0 or k > self._last:
                return best
            ax, ay = bx, by
            bx, by = pts[k]
