"""The unit of every metric a run reports (mission, per robot, AON, links), for the
tables that show them and the glossary (docs/GLOSSARY.md) that defines them.

Times are simulated seconds (the mission clock), distances metres; counts have no unit.
"""

from __future__ import annotations

SECONDS = "s"
METRES = "m"
COUNT = "count"
DBM = "dBm"

UNITS: dict[str, str] = {
    # mission and per robot
    "tasks_total": COUNT,
    "tasks_assigned": COUNT,
    "tasks_completed": COUNT,
    "tasks_failed": COUNT,
    "failed_tasks": "task ids",
    "execution_phase_time": SECONDS,
    "total_movement_time": SECONDS,
    "movement_time": SECONDS,
    "total_distance": METRES,
    "distance": METRES,
    "near_collisions": COUNT,
    "near_collisions_filtered": COUNT,
    "near_collisions_confirmed": COUNT,
    "near_collisions_false": COUNT,
    "near_collisions_missed": COUNT,
    "delay_time": SECONDS,
    "idle_time": SECONDS,
    "waiting_time": SECONDS,
    "initialisation_time": SECONDS,
    "task_execution_time": SECONDS,
    "last_task_time": SECONDS,
    "min_separation": METRES,
    "max_separation": METRES,
    "nav_aborts": COUNT,
    "made_way": COUNT,
    "queued": COUNT,
    "replans": COUNT,
    "recoveries": COUNT,
    "end_time": SECONDS,
    "successful": "yes/no",
    # the team as a whole
    "tasks_per_minute": "tasks/min",
    "assigner_connected": "fraction",
    "largest_group_mean": "fraction",
    "largest_group_min": "fraction",
    "timed_out": "yes/no",
    # Leader-Follower
    "na_movement_time": SECONDS,
    "leader_movement_time": SECONDS,
    "follower_movement_time": SECONDS,
    "regrouping_movement_time": SECONDS,
    "leader_disconnect_time": SECONDS,
    "follower_waiting_time": SECONDS,
    "role_assignment_time": SECONDS,
    "switching_time": SECONDS,
    "disconnects_detected": COUNT,
    "roles_assigned": COUNT,
    "times_leader": COUNT,
    # AON
    "publications": COUNT,
    "resend_publications": COUNT,
    "replies": COUNT,
    "restarts": COUNT,
    "pending": COUNT,
    "left_out_reports": COUNT,
    "statuses_sent": COUNT,
    "deliveries": COUNT,
    "finished": COUNT,
    "mean_finish_time": SECONDS,
    "max_finish_time": SECONDS,
    # links
    "min_distance": METRES,
    "max_distance": METRES,
    "min_rssi": DBM,
    "time_in_warning": SECONDS,
    "warnings": COUNT,
    "time_disconnected": SECONDS,
}


def unit_of(metric: str) -> str:
    """The unit of ``metric`` ("" when it has none on record)."""
    return UNITS.get(metric, "")
