"""The LF behaviour's hierarchical state machine as data — states, transitions, what
each state records on the timeline — and its parameters. The behaviour itself (what
each state does) is :mod:`mrcomm.agents.lf`; :mod:`mrcomm.agents.diagram` draws the
machine from these tables."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import field_validator

from mrcomm.agents.executor import NB_STATES, NB_TRANSITIONS
from mrcomm.agents.executor_params import ExecutorParams
from mrcomm.metrics import labels as L
from mrcomm.specs import parameter

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
    {
        "name": "reporting",
        "children": ["navigating", "avoiding"],
        "initial": "navigating",
        "transitions": [
            {"trigger": "conflict", "source": "navigating", "dest": "avoiding"},
            {"trigger": "resume", "source": "avoiding", "dest": "navigating"},
        ],
    },
]
LF_TRANSITIONS: list[dict[str, Any]] = [
    {
        "trigger": "disconnect",
        "source": ["na", "leader", "follower", "regrouping", "reporting"],
        "dest": "assigning",
    },
    {"trigger": "become_leader", "source": "assigning", "dest": "leader"},
    {"trigger": "become_follower", "source": "assigning", "dest": "follower"},
    {"trigger": "regroup", "source": "assigning", "dest": "regrouping"},
    {"trigger": "report", "source": "na", "dest": "reporting"},
    {"trigger": "reported", "source": "reporting", "dest": "na"},
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
    "reporting": L.ROLE_NA,
}


class LfParams(ExecutorParams):
    utility: str = parameter(
        "original", "the leader election's utility function (mrcomm variants utility)"
    )

    @field_validator("utility")
    @classmethod
    def _known_utility(cls, name: str) -> str:
        from mrcomm.agents.utility import utility_names

        if name not in utility_names():
            raise ValueError(f"unknown utility {name!r}; choose from {', '.join(utility_names())}")
        return name

    group_size: int = parameter(
        3,
        "most robots in one group: a role round of n members elects ceil(n/group_size) "
        "leaders and every other member follows the nearest (a team of at most this many "
        "is one group, as the original)",
        "robots",
        ge=1,
    )
    report_back: bool | None = parameter(
        None,
        "a robot with nothing left to do whose completions the task assigner missed (AON "
        "left it out) goes to find the assigner until it has them (false: it stops, as "
        "the original, and the statuses count as lost; null: on in teams of more than "
        "group_size robots)",
    )
    announce_period: float = parameter(
        0.25, "utilities and roles are published this often (4 Hz)", "s", gt=0
    )
    assign_timeout: float = parameter(
        6.0, "role assignment decides with what it collected after this long", "s", gt=0
    )
    roles_timeout: float = parameter(3.0, "stop collecting roles after this long", "s", gt=0)
    follow_distance: float = parameter(1.2, "a follower stops this close to its leader", "m", gt=0)
    refollow_distance: float = parameter(
        1.7, "and moves again when the leader is this far", "m", gt=0
    )
    await_radius: float = parameter(
        4.0,
        "in groups, a follower this close to its leader and ahead of it while the leader "
        "has a goal waits for the leader to come rather than driving at it (0: never; a "
        "team of at most group_size robots never waits: the original)",
        "m",
        ge=0,
    )
    refresh_period_near: float = parameter(
        1.0, "a follower refreshes its goal this often when the leader is near", "s", gt=0
    )
    refresh_period_far: float = parameter(
        0.4, "... and this often when the leader is beyond the warning threshold", "s", gt=0
    )
    lost_timeout: float = parameter(
        60.0, "a follower silent this long no longer holds its leader", "s", gt=0
    )
    hold_prediction: float = parameter(
        0.0,
        "a holding leader judges a follower where it should be now: its last pose moved "
        "towards the leader at its last speed for the pose's age, at most this long "
        "(0: where its last pose put it)",
        "s",
        ge=0,
    )
    hold_grace: float = parameter(
        0.0,
        "a leader holds only once a follower has been in warning this long (0: at once, "
        "as the original): the group may stretch into its connection area up to the "
        "communication limit, and a robot that drifts past it regroups",
        "s",
        ge=0,
    )
    hold_distance: float | None = parameter(
        None,
        "a leader holds while a follower is further than this from it, judged from the "
        "follower's last pose (None: while the follower's link is in warning); the original "
        "robots' leader held beyond the communication limit, 8 m (thesis Algorithm 5, "
        "lines 1541, 1606), while the warning threshold started role assignment",
        "m",
        gt=0,
    )
    hold_judges: Literal["each", "furthest"] = parameter(
        "each",
        "which followers a leader judges for a hold: each follower (a follower in warning "
        "holds the leader), or only the furthest one from it, the original's \"too far "
        "from the furthest follower robot(s)\" (thesis line 1631; Algorithm 5 judges one "
        "networkPerturbation); with a threshold that is not monotonic in distance (SSD's "
        "line-of-sight curve) a nearer follower in warning then does not hold the leader",
    )
    chain_hops: int = parameter(
        1,
        "the trigger and a leader's hold judge a mate's link over the best chain of at "
        "most this many links through the team's known positions, none in warning "
        "(path quality; use with network.relay, which carries statuses over such chains; "
        "1: the direct link only, as the original)",
        "links",
        ge=1,
        le=32,
    )
    hold_timeout: float | None = parameter(
        None,
        "a hold that no follower ends gives way after this long, and the leader then "
        "drives as long before holding again (None: a hold lasts until the followers are "
        "back, as the original; behind walls a predicted signal may warn for ever)",
        "s",
        gt=0,
    )
    group_hold_timeout: float = parameter(
        60.0,
        "hold_timeout in a team of more than group_size robots when hold_timeout is not "
        "set: a group's followers knotted around their holding leader (each making way "
        "or avoiding another) cannot end its hold",
        "s",
        gt=0,
    )
    route_check_step: float = parameter(
        0.5, "spacing of the route points a follower checks against the threshold", "m", gt=0
    )
    direct_hop: float = parameter(1.5, "length of each hop of a direct route", "m", gt=0)
    #: None waits forever.
    aon_lease: float | None = parameter(
        60.0,
        "AON: a member silent this long is reported as left out of pending messages "
        "(brought up to date when heard again); null waits forever",
        "s",
        gt=0,
    )
