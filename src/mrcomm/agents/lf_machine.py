"""The LF behaviour's hierarchical state machine as data — states, transitions, what
each state records on the timeline — and its parameters. The behaviour itself (what
each state does) is :mod:`mrcomm.agents.lf`; :mod:`mrcomm.agents.diagram` draws the
machine from these tables."""

from __future__ import annotations

from typing import Any

from pydantic import field_validator

from mrcomm.agents.executor import NB_STATES, NB_TRANSITIONS, ExecutorParams
from mrcomm.metrics import labels as L

_DRIVE = [
    {"trigger": "arrive", "source": "navigating", "dest": "executing"},
    {"trigger": "conflict", "source": "navigating", "dest": "avoiding"},
    {"trigger": "resume", "source": "avoiding", "dest": "navigating"},
    {"trigger": "nav_fail", "source": "navigating", "dest": "retrying"},
    {"trigger": "retry", "source": "retrying", "dest": "navigating"},
]
LF_STATES: list[Any] = [
    {"name": "na", "children": NB_STATES, "initial": "unassigned", "transitions": NB_TRANSITIONS},
    "assigning",
    {
        "name": "leader",
        "children": ["navigating", "avoiding", "executing", "retrying", "holding"],
        "initial": "navigating",
        "transitions": [
            *_DRIVE,
            {"trigger": "hold", "source": "navigating", "dest": "holding"},
            {"trigger": "release", "source": "holding", "dest": "navigating"},
        ],
    },
    {
        "name": "follower",
        "children": ["following", "avoiding", "waiting", "clearing"],
        "initial": "following",
        "transitions": [
            {"trigger": "conflict", "source": "following", "dest": "avoiding"},
            {"trigger": "resume", "source": "avoiding", "dest": "following"},
            {"trigger": "reach", "source": "following", "dest": "waiting"},
            {"trigger": "follow", "source": "waiting", "dest": "following"},
            {"trigger": "make_way", "source": ["following", "waiting"], "dest": "clearing"},
            {"trigger": "cleared", "source": "clearing", "dest": "following"},
        ],
    },
    "regrouping",
]
LF_TRANSITIONS: list[dict[str, Any]] = [
    {
        "trigger": "disconnect",
        "source": ["na", "leader", "follower", "regrouping"],
        "dest": "assigning",
    },
    {"trigger": "become_leader", "source": "assigning", "dest": "leader"},
    {"trigger": "become_follower", "source": "assigning", "dest": "follower"},
    {"trigger": "regroup", "source": "assigning", "dest": "regrouping"},
    {
        "trigger": "dissolve",
        "source": ["leader", "follower", "assigning", "regrouping"],
        "dest": "na",
    },
]

ACTIVITY_OF_FULL_STATE = {
    "assigning": L.ROLE_ASSIGNMENT,
    "leader_holding": L.LEADER_DISCONNECT,
    "follower_following": L.MOVING,
    "follower_waiting": L.FOLLOWER_WAITING,
    "follower_clearing": L.MOVING,
    "regrouping": L.MOVING,
}
ROLE_OF_TOP_STATE = {
    "na": L.ROLE_NA,
    "assigning": L.ROLE_ASSIGNING,
    "leader": L.ROLE_LEADER,
    "follower": L.ROLE_FOLLOWER,
    "regrouping": L.ROLE_REGROUPING,
}


class LfParams(ExecutorParams):
    utility: str = "original"

    @field_validator("utility")
    @classmethod
    def _known_utility(cls, name: str) -> str:
        from mrcomm.agents.utility import utility_names

        if name not in utility_names():
            raise ValueError(f"unknown utility {name!r}; choose from {', '.join(utility_names())}")
        return name

    announce_period: float = 0.25  # utilities and roles at 4 Hz
    assign_timeout: float = 6.0  # decide with what was collected after this long
    roles_timeout: float = 3.0  # stop collecting roles after this long
    follow_distance: float = 1.2  # a follower stops this close to the leader
    refollow_distance: float = 1.7  # and moves again when the leader is this far
    refresh_period_near: float = 1.0  # follower goal refresh when the leader is near
    refresh_period_far: float = 0.4  # ... and when it is beyond the warning threshold
    lost_timeout: float = 60.0  # a follower silent this long no longer holds the leader
    route_check_step: float = 0.5  # m between the route points a follower checks
    direct_hop: float = 1.5  # m per hop of a direct route to the leader
    #: AON: a member silent this long (no pose, no AON traffic) is reported as left out
    #: of pending messages by name instead of being waited for; it is brought up to date
    #: when heard again. None waits forever.
    aon_lease: float | None = 60.0
