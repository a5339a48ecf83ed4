"""Merging the journals of a live run into one result (``mrcomm collect``; issue 7 §3).

Every process recorded its own data (``live.journal``). This module reads a record
directory and builds the same :class:`~mrcomm.sim.mission.MissionResult` as a
simulated run, with ``config.mode = "live"``:

* each robot's timeline from its own journals — all its incarnations, a killed one's
  open intervals closed at the last time it recorded;
* failed tasks from what the task assigner recorded receiving (all its incarnations);
* message counts per agent and topic, AON statistics, from the agents' journals;
* distance, separations, links, trajectories and the robot pairs' RSSI series from the
  world's ground truth.

A ``live`` section adds what only a live run has: incarnations, pose latency
(p50/p99), the agents' lag behind the clock, each host's clock offset and, for agents
stepped on their host's clock, how that clock fared (``host_clock``).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mrcomm.agents.assignment import round_robin
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.agents.operator import apply_commands
from mrcomm.errors import InputError
from mrcomm.live.protocol import WORLD_ID
from mrcomm.messaging.aon_state import AON_COUNTERS
from mrcomm.metrics.timeline import Event, Interval, Timeline
from mrcomm.run.assemble import (
    AonAgentFacts,
    RobotTruth,
    RunFacts,
    add_relay,
    assemble,
    sum_counts,
)
from mrcomm.run.config import make_config
from mrcomm.run.proximity import Encounter
from mrcomm.run.result import MissionResult
from mrcomm.world.scenario import load_scenario


@dataclass
class JournalData:
    """One process incarnation's journal, parsed."""

    process: str
    incarnation: int
    lines: list[dict[str, Any]] = field(default_factory=list)

    def of(self, kind: str) -> list[dict[str, Any]]:
        return [line for line in self.lines if line.get("k") == kind]

    def last(self, kind: str) -> dict[str, Any] | None:
        for line in reversed(self.lines):
            if line.get("k") == kind:
                return line
        return None

    @property
    def last_time(self) -> float:
        """Latest simulated time this incarnation recorded."""
        times = [
            float(line[key])
            for line in self.lines
            for key in ("time", "sim", "t", "end")
            if isinstance(line.get(key), (int, float)) and line.get("k") != "start"
        ]
        return max(times, default=0.0)


def read_journals(record_dir: Path) -> list[JournalData]:
    if not record_dir.is_dir():
        raise InputError("not a directory", file=record_dir, field="RECORD_DIR")
    out: list[JournalData] = []
    for path in sorted(record_dir.glob("*.jsonl")):
        process, _, inc = path.stem.rpartition(".")
        if not process or not inc.isdigit():
            continue
        data = JournalData(process, int(inc))
        with path.open(encoding="utf-8") as handle:
            for raw in handle:
                raw = raw.strip()
                if not raw:
                    continue
                try:
                    data.lines.append(json.loads(raw))
                except json.JSONDecodeError:
                    break  # a line cut by a crash: everything before it stands
        if data.lines and data.lines[0].get("k") == "start":
            out.append(data)
    if not any(j.process == WORLD_ID for j in out):
        raise InputError("no world journal (world.*.jsonl) found", file=record_dir)
    return sorted(out, key=lambda j: (j.process, j.incarnation))


def record_fingerprint(record_dir: Path) -> str:
    """What identifies a live run: a SHA-256 (16 hex digits) of its journals' names and
    contents. ``collect`` of the same records gives the same fingerprint, so the run is
    stored once."""
    digest = hashlib.sha256()
    for path in sorted(record_dir.glob("*.jsonl")):
        digest.update(path.name.encode() + b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def collect(record_dir: Path) -> tuple[MissionResult, dict[str, Any]]:
    """The run's result (as ``mrcomm run`` gives it) and its live-only report."""
    journals = read_journals(record_dir)
    world = [j for j in journals if j.process == WORLD_ID][-1]
    start = world.lines[0]
    config_values = dict(start["config"])
    run = make_config(str(record_dir), **config_values)
    scenario = load_scenario(run.scenario)
    robot_ids = tuple(r.id for r in scenario.robots)
    truth = world.last("truth") or {}
    end = float(truth.get("end_time", world.last_time))
    timed_out = bool(truth.get("timed_out", True))
    by_process: dict[str, list[JournalData]] = {}
    for j in journals:
        if j.process != WORLD_ID:
            by_process.setdefault(j.process, []).append(j)

    timelines = {rid: _timeline(rid, by_process.get(rid, []), end) for rid in robot_ids}
    truth_robots = truth.get("robots", {})
    robots = {
        rid: RobotTruth(
            distance=float(tr.get("distance", 0.0)),
            min_separation=tr.get("min_separation"),
            max_separation=tr.get("max_separation"),
            replans=tr.get("replans"),
            recoveries=tr.get("recoveries"),
        )
        for rid in robot_ids
        for tr in [truth_robots.get(rid, {})]
    }
    operator_line = next(
        (j.last("operator") for j in reversed(journals) if j.process == OPERATOR_ID), None
    )
    operator = dict(operator_line["summary"]) if operator_line else {}
    # The assigner's round robin, as it assigned (assignment is not perturbed), then
    # what the operator moved or added.
    agenda = apply_commands(round_robin(scenario.tasks, robot_ids), operator.get("commands", []))
    result = assemble(
        RunFacts(
            config=run,
            scenario=scenario,
            end_time=end,
            finished=not timed_out,
            wall_time_s=float(truth.get("wall_time", 0.0)),
            timelines=timelines,
            agenda=agenda,
            received=_assigner_receipts(journals),
            robots=robots,
            counts_by_agent=_counts_by_agent(journals),
            aon=_aon_facts(journals),
            links=truth.get("links", {}),
            connectivity=truth.get("connectivity", {}),
            trajectories=_trajectories(world, robot_ids),
            rssi_series=[
                (float(line["t"]), str(a), str(b), float(v))
                for line in world.of("rssi")
                for a, b, v in line["v"]
            ],
            link_states=[
                (str(a), str(b), str(state), float(t0), float(t1))
                for a, b, state, t0, t1 in truth.get("link_states", [])
            ],
            encounters=_encounters(truth),
            relay=_relay_facts(journals),
            config_extra={"mode": "live", "speed": start.get("speed")},
        )
    )
    result.operator = operator
    report = _live_report(journals, world, by_process)
    report["record_fingerprint"] = record_fingerprint(record_dir)
    return result, report


def _relay_facts(journals: list[JournalData]) -> dict[str, dict[str, Any]]:
    """What relaying did per agent, summed over its incarnations (each journal's last
    record); empty when relaying was off."""
    out: dict[str, dict[str, Any]] = {}
    for j in journals:
        line = j.last("relay")
        if line is None:
            continue
        for agent, stats in line["agents"].items():
            add_relay(out.setdefault(agent, {}), stats)
    return out


def _encounters(truth: dict[str, Any]) -> list[Encounter] | None:
    """The world's record of robot pairs within the danger radius (None when the
    behaviour has no near-collision detection, or the journal is from before it)."""
    rows = truth.get("encounters")
    if rows is None:
        return None
    return [(str(a), str(b), float(t0), float(t1), float(d)) for a, b, t0, t1, d in rows]


# -- timelines -------------------------------------------------------------------------


def _timeline(robot: str, journals: list[JournalData], end: float) -> Timeline:
    tl = Timeline(robot)
    intervals: list[Interval] = []
    events: list[Event] = []
    ordered = sorted(journals, key=lambda j: j.incarnation)
    for k, j in enumerate(ordered):
        for line in j.lines:
            if line.get("robot") != robot:
                continue
            if line["k"] == "iv":
                intervals.append(Interval(line["track"], line["label"], line["start"], line["end"]))
            elif line["k"] == "ev":
                events.append(Event(line["time"], line["label"], dict(line.get("data") or {})))
        if j.last("end") is None:
            # Killed: close what was open at the last time it recorded (or when the next
            # incarnation started, if earlier).
            stop = j.last_time
            if k + 1 < len(ordered):
                first = ordered[k + 1].last("first_tick")
                if first is not None:
                    stop = min(stop, float(first["time"]))
            stop = min(stop, end)
            opened = j.last("open")
            for track, label, began in (opened or {}).get("intervals", []):
                if stop > began:
                    intervals.append(Interval(track, label, float(began), stop))
    tl.intervals.extend(sorted(intervals, key=lambda i: (i.start, i.track)))
    tl.events.extend(sorted(events, key=lambda e: e.time))
    return tl


# -- assigner, counts, AON ---------------------------------------------------------------


def _assigner_receipts(journals: list[JournalData]) -> set[tuple[str, str]]:
    received: set[tuple[str, str]] = set()
    for j in journals:
        for line in j.of("status_rx"):
            if line.get("state") == "SUCCESS":
                received.add((str(line["task_id"]), str(line["robot"])))
    return received


def _counts_by_agent(journals: list[JournalData]) -> dict[str, dict[str, dict[str, Any]]]:
    """Per agent and topic, summed over incarnations (each journal's last snapshot;
    with a radio also the delays)."""
    snapshots: dict[str, list[dict[str, dict[str, float]]]] = {}
    for j in journals:
        snapshot = j.last("counts")
        if snapshot is None:
            continue
        for agent, topics in snapshot["agents"].items():
            snapshots.setdefault(agent, []).append(topics)
    return {agent: sum_counts(s) for agent, s in sorted(snapshots.items())}


def _aon_facts(journals: list[JournalData]) -> dict[str, AonAgentFacts]:
    """Each agent's AON statistics: counters summed over its incarnations (each
    journal's last record), pending from the latest, every finish time."""
    out: dict[str, AonAgentFacts] = {}
    for j in journals:
        last: dict[str, dict[str, Any]] = {}
        for line in j.of("aon"):
            last[line["agent"]] = line
        for agent, line in last.items():
            facts = out.setdefault(
                agent, AonAgentFacts(counters=dict.fromkeys(AON_COUNTERS, 0), pending=0)
            )
            for k in AON_COUNTERS:
                facts.counters[k] += int(line.get(k, 0))
            facts.pending = int(line.get("pending", 0))  # the latest incarnation's
            facts.finish_times.extend(float(x) for x in line.get("finish_times", []))
    return out


def _trajectories(world: JournalData, robot_ids: tuple[str, ...]) -> dict[str, list[Any]]:
    out: dict[str, list[tuple[float, float, float]]] = {rid: [] for rid in robot_ids}
    for line in world.of("traj"):
        for rid, (x, y) in line["p"].items():
            if rid in out:
                out[rid].append((float(line["t"]), float(x), float(y)))
    return {rid: sorted(points) for rid, points in out.items()}


# -- the live report ----------------------------------------------------------------------


def _live_report(
    journals: list[JournalData], world: JournalData, by_process: dict[str, list[JournalData]]
) -> dict[str, Any]:
    world_wall = {round(float(c["sim"]), 3): float(c["wall"]) for c in world.of("clock")}
    latency: list[float] = []
    processes: dict[str, Any] = {}
    for process, js in sorted(by_process.items()):
        lags = [float(line["max_lag"]) for j in js for line in j.of("lag")]
        offsets = [
            float(c["wall"]) - world_wall[round(float(c["sim"]), 3)]
            for j in js
            for c in j.of("clock")
            if round(float(c["sim"]), 3) in world_wall
        ]
        for j in js:
            for line in j.of("pose_latency"):
                latency.extend(float(x) for x in line["samples"])
        processes[process] = {
            "incarnations": [j.incarnation for j in js],
            "host": js[-1].lines[0].get("host"),
            "finished": [j.last("end") is not None for j in js],
            "resynced": [j.last("resync") is not None for j in js],
            "max_lag_s": max(lags) if lags else None,
            # When this host's agent clock read a time minus when the world's did: the
            # hosts' clock offset plus the transport latency (shared clock: of each
            # tick; host clock: of the first tick, which set the mission start).
            "clock_offset_s": round(float(np.median(offsets)), 6) if offsets else None,
            "host_clock": _host_clock(js),
            # ESD: readings of the robot's own pulse that fed its sensor (all incarnations).
            "pulse_readings": _pulse_readings(js),
            # Samples from peers the bus edge refused, by cause (all incarnations).
            "refused": _refused(js),
            "left_out": [
                {"time": line["time"], "msg": line["msg"], "absent": line["absent"]}
                for j in js
                for line in j.of("left_out")
            ],
        }
    report: dict[str, Any] = {"processes": processes}
    report["pose_latency_ms"] = _percentiles(latency)
    return report


def _host_clock(js: list[JournalData]) -> dict[str, Any] | None:
    """An agent stepped on its host's clock (``live.host_clock``): steps skipped (ran
    more than a step late), the worst lateness of a step, and how stale its base state
    got (its time minus the latest world tick's); None for a shared-clock agent."""
    lasts = []  # each incarnation's last host-clock line (its counters are cumulative)
    for j in js:
        lines = [c for c in j.of("clock") if "base_age" in c]
        if lines:
            lasts.append(lines[-1])
    if not lasts:
        return None
    return {
        "skipped_steps": sum(int(line["skipped"]) for line in lasts),
        "max_late_s": max(float(line["late"]) for line in lasts),
        "max_base_age_s": max(float(line["max_base_age"]) for line in lasts),
    }


def _pulse_readings(js: list[JournalData]) -> int | None:
    """Pulse readings an agent took, summed over its incarnations (None: no ESD)."""
    lasts = [line for line in (j.last("pulse") for j in js) if line is not None]
    return sum(int(line["readings"]) for line in lasts) if lasts else None


def _refused(js: list[JournalData]) -> dict[str, int]:
    """Samples the bus edge refused, by cause, summed over the incarnations."""
    out: dict[str, int] = {}
    for j in js:
        line = j.last("refused")
        if line is not None:
            for cause, count in line["causes"].items():
                out[cause] = out.get(cause, 0) + int(count)
    return dict(sorted(out.items()))


def _percentiles(samples: list[float]) -> dict[str, Any]:
    if not samples:
        return {"n": 0}
    a = np.asarray(samples) * 1000.0
    return {
        "n": int(a.size),
        "p50": round(float(np.percentile(a, 50)), 3),
        "p95": round(float(np.percentile(a, 95)), 3),
        "p99": round(float(np.percentile(a, 99)), 3),
        "max": round(float(a.max()), 3),
    }


def live_summary(result: MissionResult, report: dict[str, Any]) -> dict[str, Any]:
    """The JSON of ``mrcomm live --json``: the run summary plus the live report."""
    summary = result.summary()
    summary["live"] = report
    return summary
