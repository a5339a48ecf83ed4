"""The result of one run, the same for every mode: metrics per mission and robot,
message counts, AON statistics, link summaries, timelines and trajectories."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from mrcomm.metrics.timeline import Timeline
from mrcomm.world.scenario import Scenario


@dataclass
class MissionResult:
    """Everything a run produced. ``summary()`` is the JSON of ``mrcomm run --json``."""

    config: dict[str, Any]
    mission: dict[str, Any]
    robots: dict[str, dict[str, Any]]
    messages: dict[str, dict[str, Any]]
    messages_by_agent: dict[str, dict[str, dict[str, float]]]
    aon: dict[str, Any]
    links: dict[str, dict[str, Any]]
    sim_time_s: float
    wall_time_s: float
    timelines: dict[str, Timeline]
    #: Each robot's sampled (t, x, y): a :class:`~mrcomm.run.trajectory.Trajectory` from
    #: the simulation, lists from a live run's journals.
    trajectories: Mapping[str, Sequence[tuple[float, float, float]]]
    scenario: Scenario
    #: (time, from, to, rssi dBm) for robot pairs at 2 Hz, when the threshold has RSSI.
    rssi_series: list[tuple[float, str, str, float]]
    #: (robot a, robot b, "warning" | "out of range", start s, end s) per robot pair.
    link_states: list[tuple[str, str, str, float, float]] = field(default_factory=list)
    #: What relaying did per node (:meth:`mrcomm.net.relay.Relay.stats`; empty when off).
    relay: dict[str, Any] = field(default_factory=dict)
    #: The operator's commands (:meth:`mrcomm.agents.operator.Operator.summary`; empty
    #: without an operator).
    operator: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        relay = {"relay": self.relay} if self.relay else {}
        operator = {"operator": self.operator} if self.operator else {}
        return {
            "config": self.config,
            "mission": self.mission,
            "robots": self.robots,
            "messages": self.messages,
            "messages_by_agent": self.messages_by_agent,
            "aon": self.aon,
            "links": self.links,
            "sim_time_s": self.sim_time_s,
            "wall_time_s": self.wall_time_s,
            **relay,
            **operator,
        }
