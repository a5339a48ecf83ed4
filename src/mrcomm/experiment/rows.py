"""Turn one run's outcome into the rows of the results tables (tables.py).

Runs in the worker process, so that only small, plain tuples travel back to the
parent (never the MissionResult with its scenario and map), and so that the machine
recorded is the one that ran the mission. Column orders are those of
:mod:`mrcomm.experiment.tables`; ``finished_at`` is left to the parent, which stamps
it when it writes the run.
"""

from __future__ import annotations

import json
import math
from typing import Any

from mrcomm.experiment.schema import RunSpec
from mrcomm.experiment.tables import (
    RUN_AON_COLUMNS,
    RUN_METRIC_COLUMNS,
    RUN_TABLES,
    TRAJECTORY_STORE_PERIOD,
)
from mrcomm.net.delivery import COUNT_KEYS, DELAY_KEYS, SHARED_KEYS
from mrcomm.run.provenance import fingerprint, provenance
from mrcomm.run.result import MissionResult
from mrcomm.specs import get_spec

#: table name -> rows (tuples in the table's column order).
Rows = dict[str, list[tuple[Any, ...]]]


def _config_part(spec: RunSpec, status: str, error: str | None) -> tuple[Any, ...]:
    c = spec.config
    return (
        spec.run_id,
        spec.config_id,
        spec.experiment,
        spec.label,
        spec.scenario_name,
        c.network,
        float(c.spl),
        c.threshold,
        c.behaviour,
        spec.repetition,
        spec.seed,
        spec.mode,
        status,
        error,
    )


def _number(value: Any) -> float | None:
    """Metric value as a float (NULL for missing or non-finite values)."""
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float) and math.isfinite(value):
        return float(value)
    return None


def _provenance_part(spec: RunSpec, run_fingerprint: str | None = None) -> tuple[Any, ...]:
    """The provenance columns; the fingerprint is the configuration's, seed's and
    inputs' unless the caller knows better (a live run: its record)."""
    info = provenance(spec.config)
    hashes = info["input_hashes"]
    return (
        info["mrcomm_version"],
        info["git_commit"],
        info["machine"],
        json.dumps(hashes, sort_keys=True),
        run_fingerprint or fingerprint(spec.config_id, spec.seed, hashes),
    )


def failure_rows(spec: RunSpec, status: str, error: str, wall_time_s: float | None) -> Rows:
    """Rows of a run that crashed or ran out of time: a runs row, nothing else."""
    n_rest = len(RUN_METRIC_COLUMNS) + len(RUN_AON_COLUMNS) + 1  # + finished_at
    runs = (
        *_config_part(spec, status, error),
        None,
        wall_time_s,
        *([None] * n_rest),
        *_provenance_part(spec),
    )
    return {"runs": [runs]}


def result_rows(
    spec: RunSpec, result: MissionResult, wall_time_s: float, run_fingerprint: str | None = None
) -> Rows:
    """Every table's rows for a finished mission."""
    rid = spec.run_id
    mission = result.mission
    metrics: list[Any] = []
    for _, _, key in RUN_METRIC_COLUMNS:
        value = mission.get(key)
        metrics.append(len(value or ()) if key == "failed_tasks" else value)
    total = result.aon.get("total", {})
    aon = [total.get(key) if total else None for _, _, key in RUN_AON_COLUMNS]
    runs = (
        *_config_part(spec, "ok", None),
        result.sim_time_s,
        wall_time_s,
        *metrics,
        *aon,
        None,  # finished_at: stamped by the parent
        *_provenance_part(spec, run_fingerprint),
    )
    rows: Rows = {"runs": [runs]}
    columns = {key for _, _, key in RUN_METRIC_COLUMNS}
    behaviour = get_spec("behaviour", spec.config.behaviour)
    rows["team_metrics"] = [
        (rid, metric.name, _number(mission.get(metric.name)))
        for metric in behaviour.team_metrics
        if metric.name not in columns
    ]
    rows["robot_metrics"] = [
        (rid, robot, metric, _number(value))
        for robot, values in result.robots.items()
        for metric, value in values.items()
        if value is None or isinstance(value, int | float)
    ]
    rows["failed_tasks"] = [
        (rid, str(task), robot)
        for robot, values in result.robots.items()
        for task in values.get("failed_tasks") or []
    ]
    # The radio's causes and delays are NULL for runs of network models without a radio,
    # the shared channel's for runs without it.
    rows["messages"] = [
        (
            rid,
            agent,
            topic,
            *(c.get(key) for key in COUNT_KEYS),
            *(c.get(key) for key in DELAY_KEYS),
            *(c.get(key) for key in SHARED_KEYS),
        )
        for agent, topics in result.messages_by_agent.items()
        for topic, c in topics.items()
    ]
    rows["links"] = []
    for pair, s in result.links.items():
        src, _, dst = pair.partition("->")
        rows["links"].append(
            (
                rid,
                src,
                dst,
                _number(s.get("min_distance")),
                _number(s.get("max_distance")),
                _number(s.get("min_rssi")),
                _number(s.get("time_in_warning")),
                s.get("warnings"),
                _number(s.get("time_disconnected")),
            )
        )
    rows["intervals"] = [
        (rid, robot, i.track, i.label, i.start, i.end)
        for robot, timeline in result.timelines.items()
        for i in timeline.intervals
    ]
    rows["events"] = [
        (rid, robot, e.time, e.label, json.dumps(e.data, sort_keys=True, default=str))
        for robot, timeline in result.timelines.items()
        for e in timeline.events
    ]
    # The operator's commands, as events of the agent "operator" (label command_sent;
    # what became of each in data: acknowledgements, when AON finished it).
    rows["events"] += [
        (rid, "operator", c["time"], "command_sent",
         json.dumps({k: v for k, v in c.items() if k != "time"}, sort_keys=True))
        for c in result.operator.get("commands", [])
    ]  # fmt: skip
    rows["rssi"] = [(rid, t, src, dst, rssi) for t, src, dst, rssi in result.rssi_series]
    rows["link_states"] = [(rid, *interval) for interval in result.link_states]
    every = TRAJECTORY_STORE_PERIOD
    rows["trajectories"] = [
        (rid, robot, t, x, y)
        for robot, samples in result.trajectories.items()
        for t, x, y in samples
        # Samples on the store period's grid (the recorded ones are finer).
        if abs(t / every - round(t / every)) < 1e-6
    ]
    return rows


def check_rows(rows: Rows) -> None:
    """Raise ValueError when a table is unknown or a row has the wrong width (a bug)."""
    for table, table_rows in rows.items():
        width = len(RUN_TABLES[table])
        for row in table_rows:
            if len(row) != width:
                raise ValueError(f"{table}: row of {len(row)} values, expected {width}")
