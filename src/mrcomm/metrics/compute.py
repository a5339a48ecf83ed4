"""The metrics of a run, computed from per-robot timelines.

Team totals are sums of what each robot recorded about itself (distributed data
recording), so a near collision between two robots counts once for each of them, as in
the original study.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from mrcomm.metrics import labels as L
from mrcomm.metrics.timeline import ACTIVITY, ROLE, Timeline

#: A robot's judged near collisions checked against ground truth (confirmed, false
#: alarms) and the true ones it did not judge (:mod:`mrcomm.run.proximity`).
TRUTH_COUNTS = ("near_collisions_confirmed", "near_collisions_false", "near_collisions_missed")


@dataclass(frozen=True)
class RobotFacts:
    """What the simulator (or the robot's own odometry) knows beyond the timeline."""

    distance: float  # odometry distance travelled (m)
    min_separation: float | None  # closest team mate, minimum over the run (m); None alone
    max_separation: float | None  # furthest team mate, maximum over the run (m)
    tasks_assigned: int
    tasks_failed: int


def robot_metrics(timeline: Timeline, facts: RobotFacts) -> dict[str, Any]:
    """Per-robot metrics (all times in seconds)."""
    assignment = timeline.first(L.ASSIGNMENT_RECEIVED)
    started = timeline.first(L.STARTED_MOVING)
    init_time = (
        started.time - assignment.time if (assignment is not None and started is not None) else None
    )
    collisions = [e for e in timeline.events if e.label == L.NEAR_COLLISION]
    last_completion = timeline.last(L.TASK_COMPLETED)
    return {
        "tasks_assigned": facts.tasks_assigned,
        # Distinct tasks: a restarted robot (a new live incarnation) may do one again.
        "tasks_completed": len(completed_tasks(timeline)),
        "tasks_failed": facts.tasks_failed,
        "initialisation_time": init_time,
        "movement_time": timeline.total(L.MOVING),
        "task_execution_time": timeline.total(L.TASK),
        "delay_time": timeline.total(L.DELAY),
        "idle_time": timeline.total(L.IDLE),
        "waiting_time": timeline.total(L.WAITING),
        "distance": facts.distance,
        "near_collisions": len(collisions),
        "near_collisions_filtered": sum(1 for e in collisions if not e.data.get("repeat")),
        "nav_aborts": timeline.count(L.NAV_ABORTED),
        "made_way": timeline.count(L.MADE_WAY),
        "queued": timeline.count(L.QUEUED),
        "last_task_time": last_completion.time if last_completion else None,
        "min_separation": facts.min_separation,
        "max_separation": facts.max_separation,
    }


def overlap(timeline: Timeline, activity: str, role: str) -> float:
    """Time spent in ``activity`` (activity track) while holding ``role`` (role track)."""
    acts = [i for i in timeline.intervals if i.track == ACTIVITY and i.label == activity]
    roles = [i for i in timeline.intervals if i.track == ROLE and i.label == role]
    total = 0.0
    for a in acts:
        for r in roles:
            total += max(0.0, min(a.end, r.end) - max(a.start, r.start))
    return total


def switching_time(timeline: Timeline) -> float:
    """Time from each role change (roles assigned or dissolved) until the robot moves
    again, when it moves before the next change: stopping, re-planning, restarting."""
    changes = sorted(
        e.time for e in timeline.events if e.label in (L.ROLE_ASSIGNED, L.ROLES_DISSOLVED)
    )
    starts = sorted(
        i.start for i in timeline.intervals if i.track == ACTIVITY and i.label == L.MOVING
    )
    total = 0.0
    for k, t in enumerate(changes):
        horizon = changes[k + 1] if k + 1 < len(changes) else float("inf")
        nxt = next((s for s in starts if s >= t), None)
        if nxt is not None and nxt < horizon:
            total += nxt - t
    return total


def lf_metrics(timeline: Timeline) -> dict[str, Any]:
    """Leader-Follower metrics of one robot."""
    return {
        "na_movement_time": overlap(timeline, L.MOVING, L.ROLE_NA),
        "leader_movement_time": overlap(timeline, L.MOVING, L.ROLE_LEADER),
        "follower_movement_time": overlap(timeline, L.MOVING, L.ROLE_FOLLOWER),
        "regrouping_movement_time": overlap(timeline, L.MOVING, L.ROLE_REGROUPING),
        "leader_disconnect_time": timeline.total(L.LEADER_DISCONNECT),
        "follower_waiting_time": timeline.total(L.FOLLOWER_WAITING),
        "role_assignment_time": timeline.total(L.ROLE_ASSIGNMENT),
        "switching_time": switching_time(timeline),
        "disconnects_detected": timeline.count(L.DISCONNECT_DETECTED),
        "roles_assigned": timeline.count(L.ROLE_ASSIGNED),
        "times_leader": sum(
            1
            for e in timeline.events
            if e.label == L.ROLE_ASSIGNED and e.data.get("leader") == timeline.owner
        ),
    }


def lf_wait_metrics(timeline: Timeline) -> dict[str, Any]:
    """lf-wait's metrics of one robot: LF's, and its detours."""
    return {
        **lf_metrics(timeline),
        "detours": timeline.count(L.DETOUR),
        "detour_tasks": sum(
            1
            for e in timeline.events
            if e.label == L.DETOUR_ENDED and e.data.get("how") == "completed"
        ),
        "leader_detour_wait_time": timeline.total(L.LEADER_DETOUR_WAIT),
    }


def rps_metrics(timeline: Timeline) -> dict[str, Any]:
    """rps's metrics of one robot: its rendezvous, the time spent waiting at the
    meeting point, and how many statuses it published again there."""
    return {
        "rendezvous_count": timeline.count(L.RENDEZVOUS_START),
        "rendezvous_time": timeline.total(L.RENDEZVOUS),
        "statuses_reshared": sum(
            int(e.data.get("count", 0)) for e in timeline.events if e.label == L.STATUSES_RESHARED
        ),
    }


def serried_metrics(timeline: Timeline) -> dict[str, Any]:
    """serried's metric of one robot: the time it held the group as its leader."""
    return {"group_hold_time": timeline.total(L.LEADER_DISCONNECT)}


def completed_tasks(timeline: Timeline) -> set[str]:
    """Ids of the tasks a robot completed (each once, however often it did it)."""
    return {str(e.data.get("task_id")) for e in timeline.events if e.label == L.TASK_COMPLETED}


def execution_phase(timelines: Mapping[str, Timeline]) -> tuple[float | None, float | None]:
    """(start, end) of the execution phase: every robot has its assignment -> the last
    task completed. ``None`` where it never began or no task was completed."""
    received = [tl.first(L.ASSIGNMENT_RECEIVED) for tl in timelines.values()]
    if not received or any(e is None for e in received):
        return None, None
    start = max(e.time for e in received if e is not None)
    completions = [
        e.time for tl in timelines.values() for e in tl.events if e.label == L.TASK_COMPLETED
    ]
    return start, (max(completions) if completions else None)


def mission_metrics(
    robots: Mapping[str, dict[str, Any]],
    timelines: Mapping[str, Timeline],
    *,
    tasks_total: int,
    failed_tasks: list[str],
    team_metrics: Sequence[str] = (),
) -> dict[str, Any]:
    """Team metrics: totals / extremes over the per-robot metrics; ``team_metrics``:
    those the behaviour adds (its spec's), each the total of its robots' metric."""
    start, end = execution_phase(timelines)
    rows = list(robots.values())

    def total(key: str) -> float:
        return float(sum(r[key] for r in rows))

    return {
        "successful": not failed_tasks and start is not None,
        "failed_tasks": sorted(failed_tasks, key=_task_sort_key),
        "tasks_total": tasks_total,
        "tasks_completed": len(set().union(*(completed_tasks(tl) for tl in timelines.values()))),
        "execution_phase_time": (end - start) if (start is not None and end is not None) else None,
        "total_movement_time": total("movement_time"),
        "total_distance": total("distance"),
        "near_collisions": int(total("near_collisions")),
        "near_collisions_filtered": int(total("near_collisions_filtered")),
        "delay_time": total("delay_time"),
        "idle_time": total("idle_time"),
        "task_execution_time": total("task_execution_time"),
        **{k: int(total(k)) for k in TRUTH_COUNTS if rows and k in rows[0]},
        **{k: total(k) for k in team_metrics if rows and k in rows[0]},
        "min_separation": min(
            (r["min_separation"] for r in rows if r["min_separation"] is not None), default=None
        ),
        "max_separation": max(
            (r["max_separation"] for r in rows if r["max_separation"] is not None), default=None
        ),
    }


def _task_sort_key(task_id: str) -> tuple[int, str]:
    # Numeric ids sort numerically ('2' before '10'); others after, alphabetically.
    return (int(task_id), "") if task_id.isdigit() else (1 << 30, task_id)
