"""The one result assembler of every mode: the facts a run collected in, its metrics out.

A simulated run (:meth:`mrcomm.sim.mission.Mission.result`) and a live run
(:func:`mrcomm.live.collect.collect`, from the journals of its processes) gather the
same :class:`RunFacts` — timelines, what the task assigner received, message counts,
AON statistics, each robot's ground truth, links, trajectories — and this module turns
them into the same :class:`~mrcomm.run.result.MissionResult`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.metrics import labels as L
from mrcomm.metrics.compute import RobotFacts, mission_metrics, robot_metrics
from mrcomm.metrics.timeline import Timeline
from mrcomm.net.delivery import count_keys, has_radio_counts, has_shared_counts
from mrcomm.run.config import RunConfig
from mrcomm.run.proximity import Encounter, collision_zone, judged_against_truth
from mrcomm.run.result import MissionResult
from mrcomm.world.scenario import Scenario

#: AON counters summed over agents into the run's total.
AON_TOTAL_KEYS = (
    "publications",
    "resend_publications",
    "replies",
    "restarts",
    "pending",
    "left_out_reports",
)


@dataclass
class RobotTruth:
    """What the robot's body (the simulator or the live world) knows of one robot."""

    distance: float
    min_separation: float | None
    max_separation: float | None
    replans: int | None = None
    recoveries: int | None = None


@dataclass
class AonAgentFacts:
    """One agent's AON statistics: its counters (``AonStats.counters()``, summed over
    incarnations), messages still pending, and the finish time of each message."""

    counters: dict[str, int]
    pending: int
    finish_times: list[float] = field(default_factory=list)


@dataclass
class RunFacts:
    """Everything a run collected that its result is computed from."""

    config: RunConfig
    scenario: Scenario
    end_time: float
    finished: bool
    wall_time_s: float
    timelines: dict[str, Timeline]
    #: The tasks each robot was assigned (the task assigner's agenda).
    agenda: Mapping[str, Sequence[Any]]
    #: (task_id, robot) pairs whose completion reached the task assigner.
    received: set[tuple[str, str]]
    robots: dict[str, RobotTruth]
    counts_by_agent: dict[str, dict[str, dict[str, float]]]
    aon: dict[str, AonAgentFacts]
    links: dict[str, dict[str, Any]]
    trajectories: Mapping[str, Sequence[tuple[float, float, float]]]
    #: (time, from, to, rssi dBm) samples of robot pairs.
    rssi_series: list[tuple[float, str, str, float]]
    #: (robot a, robot b, state, start, end): when each pair's link warned or was out of
    #: range (:meth:`mrcomm.net.links.LinkRecorder.state_intervals`).
    link_states: list[tuple[str, str, str, float, float]] = field(default_factory=list)
    #: The team's largest connected group (:meth:`LinkRecorder.connectivity`; empty
    #: from a live record written before it was recorded).
    connectivity: dict[str, float | None] = field(default_factory=dict)
    #: When robot pairs were within the danger radius of each other (ground truth,
    #: :class:`mrcomm.run.proximity.ProximityRecorder`); None: not recorded.
    encounters: list[Encounter] | None = None
    #: What relaying did per node (empty when the network does not relay).
    relay: dict[str, Any] = field(default_factory=dict)
    #: Configuration entries only one mode has (a live run's mode and speed).
    config_extra: dict[str, Any] = field(default_factory=dict)


def assemble(facts: RunFacts) -> MissionResult:
    """The run's result (what ``mrcomm run --json`` prints) from its facts."""
    robot_ids = tuple(facts.robots)
    failed_pairs = [
        (task.task_id, rid)
        for rid in robot_ids
        for task in facts.agenda[rid]
        if (task.task_id, rid) not in facts.received
    ]
    behaviour = facts.config.spec("behaviour")
    behaviour_metrics = behaviour.robot_metrics_function()
    robots: dict[str, dict[str, Any]] = {}
    zone = collision_zone(facts.config)
    for rid in robot_ids:
        truth = facts.robots[rid]
        robot_facts = RobotFacts(
            distance=truth.distance,
            min_separation=truth.min_separation,
            max_separation=truth.max_separation,
            tasks_assigned=len(facts.agenda[rid]),
            tasks_failed=sum(1 for _, robot in failed_pairs if robot == rid),
        )
        metrics = robot_metrics(facts.timelines[rid], robot_facts)
        if facts.encounters is not None and zone is not None:
            metrics.update(judged_against_truth(facts.timelines[rid], facts.encounters, zone[1]))
        if behaviour_metrics is not None:
            metrics.update(behaviour_metrics(facts.timelines[rid]))
        metrics["failed_tasks"] = [t for t, robot in failed_pairs if robot == rid]
        metrics["replans"] = truth.replans
        metrics["recoveries"] = truth.recoveries
        robots[rid] = rounded(metrics)
    mission = mission_metrics(
        robots,
        facts.timelines,
        # The tasks of the final agenda: an operator may have added some.
        tasks_total=len({t.task_id for tasks in facts.agenda.values() for t in tasks}),
        failed_tasks=list(dict.fromkeys(t for t, _ in failed_pairs)),
        team_metrics=[m.name for m in behaviour.team_metrics],
    )
    mission.update(team_scale(facts, mission))
    mission["timed_out"] = not facts.finished
    mission["end_time"] = round(facts.end_time, 6)
    config = facts.config.model_dump(mode="json")
    config["label"] = facts.config.label()
    config["scenario_name"] = facts.scenario.name
    config.update(facts.config_extra)
    by_agent = {
        agent: dict(sorted(topics.items()))
        for agent, topics in sorted(facts.counts_by_agent.items())
    }
    return MissionResult(
        config=config,
        mission=rounded(mission),
        robots=robots,
        messages=sum_counts(by_agent.values()),
        messages_by_agent=by_agent,
        aon=aon_summary(facts.aon, facts.timelines),
        links=facts.links,
        sim_time_s=round(facts.end_time, 6),
        wall_time_s=facts.wall_time_s,
        timelines=facts.timelines,
        trajectories=facts.trajectories,
        scenario=facts.scenario,
        rssi_series=[(round(t, 3), a, b, round(v, 3)) for t, a, b, v in facts.rssi_series],
        link_states=list(facts.link_states),
        relay=relay_summary(facts.relay),
    )


def team_scale(facts: RunFacts, mission: Mapping[str, Any]) -> dict[str, float | None]:
    """The metrics that tell how a large team did as a team: its work rate (tasks
    completed per minute of the execution phase), how much of the time its robots could
    reach the task assigner (the mean over robots of the fraction of the run each one's
    link to the assigner was connected; 1 for the robot hosting it), and its largest
    connected group (mean and minimum, as a fraction of the team)."""
    phase = mission.get("execution_phase_time")
    per_minute = mission["tasks_completed"] / (phase / 60.0) if phase else None
    fractions = []
    for rid in facts.robots:
        link = facts.links.get(f"{rid}->{ASSIGNER_ID}")
        if link is None:  # the robot hosting the assigner (or no assigner link recorded)
            fractions.append(1.0 if facts.scenario.assigner.host == rid else None)
        elif facts.end_time > 0:
            fractions.append(1.0 - float(link["time_disconnected"]) / facts.end_time)
    known = [f for f in fractions if f is not None]
    return {
        "tasks_per_minute": per_minute,
        "assigner_connected": sum(known) / len(known) if known else None,
        "largest_group_mean": facts.connectivity.get("largest_group_mean"),
        "largest_group_min": facts.connectivity.get("largest_group_min"),
    }


def relay_summary(per_node: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """Relaying per node and in total: copies passed on, copies received first,
    duplicates dropped, and the hop counts of the messages received first."""
    if not per_node:
        return {}
    total: dict[str, Any] = {}
    for stats in per_node.values():
        add_relay(total, stats)
    total["hops"] = dict(sorted(total["hops"].items(), key=lambda item: int(item[0])))
    return {"total": total, "nodes": dict(per_node)}


def add_relay(into: dict[str, Any], stats: Mapping[str, Any]) -> None:
    """Add one node's relaying counts (or one incarnation's) to ``into``."""
    for key in ("passed_on", "received_copies", "duplicates"):
        into[key] = into.get(key, 0) + int(stats[key])
    hops = into.setdefault("hops", {})
    for hop, n in stats["hops"].items():
        hops[hop] = hops.get(hop, 0) + int(n)


def sum_counts(
    per_agent: Iterable[Mapping[str, Mapping[str, float]]],
) -> dict[str, dict[str, Any]]:
    """Totals per topic over several agents' counts (with a radio, also the mean and
    largest delay of the messages received)."""
    per_agent = list(per_agent)
    # The radio's causes appear only in runs with a radio (present in the agents' counts).
    radio = has_radio_counts(c for counts in per_agent for c in counts.values())
    shared = has_shared_counts(c for counts in per_agent for c in counts.values())
    keys = count_keys(radio, shared)
    totals: dict[str, dict[str, Any]] = {}
    for counts in per_agent:
        for topic, c in counts.items():
            t = totals.setdefault(topic, dict.fromkeys(keys, 0))
            for k in keys:
                t[k] += int(c.get(k, 0))
            if shared:  # the seconds the topic's messages took on the air
                t["airtime_s"] = round(t.get("airtime_s", 0.0) + c.get("airtime_s", 0.0), 6)
            if radio:  # received-weighted mean and maximum of the radio delay
                t["delay_total"] = t.get("delay_total", 0.0) + c.get("delay_mean_s", 0.0) * int(
                    c.get("received", 0)
                )
                t["delay_max_s"] = max(t.get("delay_max_s", 0.0), c.get("delay_max_s", 0.0))
    for t in totals.values():
        if "delay_total" in t:
            total = t.pop("delay_total")
            t["delay_mean_s"] = round(total / t["received"], 6) if t["received"] else 0.0
            t["delay_max_s"] = round(t["delay_max_s"], 6)
    return dict(sorted(totals.items()))


def aon_summary(
    agents: Mapping[str, AonAgentFacts], timelines: Mapping[str, Timeline]
) -> dict[str, Any]:
    """AON statistics per agent and in total (empty when statuses go plain)."""
    if not agents:
        return {}
    per_agent: dict[str, dict[str, Any]] = {}
    for agent, stats in sorted(agents.items()):
        times = stats.finish_times
        per_agent[agent] = {
            **stats.counters,
            "pending": stats.pending,
            "mean_finish_time": round(sum(times) / len(times), 6) if times else None,
            "max_finish_time": round(max(times), 6) if times else None,
        }
    rows = per_agent.values()
    finish = [r["max_finish_time"] for r in rows if r["max_finish_time"] is not None]
    total: dict[str, Any] = {k: sum(int(r.get(k, 0)) for r in rows) for k in AON_TOTAL_KEYS}
    total["statuses_sent"] = sum(
        1 for tl in timelines.values() for e in tl.events if e.label == L.TASK_COMPLETED
    )
    total["max_finish_time"] = max(finish) if finish else None
    return {"total": total, "agents": per_agent}


def rounded(metrics: dict[str, Any]) -> dict[str, Any]:
    """Six decimals for finite floats: stable JSON, far below any physical meaning."""
    return {
        k: (round(v, 6) if isinstance(v, float) and math.isfinite(v) else v)
        for k, v in metrics.items()
    }
