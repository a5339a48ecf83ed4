"""LF's geometry of following: whether a follower's planned route leaves the
connection area around its leader and the straight hop it takes instead, where a
holding leader judges a follower to be by now (``hold_prediction``), and whether the
leader is coming the follower's way (``await_radius``)."""

from __future__ import annotations

import itertools
import math

from mrcomm.agents.collision import Mate
from mrcomm.agents.making_way import ahead_of
from mrcomm.ports import Base, LinkSensor
from mrcomm.world.geometry import Pose, polyline_length


def route_leaves_connection(
    sensor: LinkSensor,
    leader: str,
    route: tuple[tuple[float, float], ...],
    leader_at: tuple[float, float],
    step: float,
    now: float,
) -> bool:
    """Whether some point of ``route`` (checked every ``step`` m) is in warning from
    the leader at ``leader_at``: the planner must not route a follower out of range."""
    for (x0, y0), (x1, y1) in itertools.pairwise(route):
        n = max(1, math.ceil(math.hypot(x1 - x0, y1 - y0) / step))
        for k in range(1, n + 1):
            x, y = x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n
            if sensor.warning(leader, Pose(x, y), *leader_at, now):
                return True
    return False


def direct_hop(
    base: Base,
    sensor: LinkSensor,
    leader: str,
    target: tuple[float, float],
    check_step: float,
    hop_length: float,
    now: float,
) -> tuple[float, float] | None:
    """Where a follower drives instead of its leader's position ``target``: when it is
    in the connection area and the planned route would take it out (some point in
    warning from the leader), one hop of ``hop_length`` straight at the leader, if the
    straight line is open there (a route to the hop at most 25 % longer). None: take
    the planned route (outside the area, or the straight line is blocked and the
    route is the only way)."""
    pose = base.pose
    if sensor.warning(leader, pose, *target, now):
        return None
    route = base.make_plan(*target)
    if route is None or not route_leaves_connection(sensor, leader, route, target, check_step, now):
        return None
    dx, dy = target[0] - pose.x, target[1] - pose.y
    distance = math.hypot(dx, dy)
    scale = min(hop_length, distance) / max(distance, 1e-9)
    hop = (pose.x + dx * scale, pose.y + dy * scale)
    hop_route = base.make_plan(*hop)
    straight = math.hypot(hop[0] - pose.x, hop[1] - pose.y)
    if hop_route is not None and polyline_length(hop_route) <= 1.25 * straight + 0.1:
        return hop
    return None


def predicted_follower(
    known: Mate, pose: Pose, age: float, horizon: float, follow_distance: float
) -> tuple[float, float]:
    """Where a follower should be now: a follower drives to its leader (at ``pose``),
    so its last pose is moved straight towards the leader at the speed it had, for the
    pose's ``age`` (at most ``horizon`` s), stopping at the follow distance. The hold
    then ends on geometry — the follower back inside the warning threshold — and not
    on the arrival of the one pose that says so, which under loss may take seconds. A
    follower that had stopped is predicted where it stood. Judged against
    straight-line travel: a follower that must go round a wall is predicted closer than
    it is, and the leader may move on early by up to the horizon's travel (0.26 m/s x
    horizon)."""
    if horizon <= 0:
        return known.x, known.y
    dx, dy = pose.x - known.x, pose.y - known.y
    gap = math.hypot(dx, dy)
    travel = min(abs(known.v) * min(age, horizon), max(0.0, gap - follow_distance))
    if travel <= 0.0:
        return known.x, known.y
    return known.x + dx * travel / gap, known.y + dy * travel / gap


def leader_coming(pose: Pose, leader: Mate | None, distance: float, radius: float) -> bool:
    """Whether a follower at ``pose``, ``distance`` m from its leader, lies ahead of the
    leader within ``radius`` while the leader has a goal: the leader is coming its way,
    so the follower waits for it rather than driving at it. (Driving at it, followers
    met their leaders head-on in doors: followers outside a room pushed in towards their
    leaders while the leaders, and other groups' followers, pushed out.)"""
    if leader is None or leader.goal_dist < 0 or distance >= radius:
        return False
    return ahead_of(pose, leader)
