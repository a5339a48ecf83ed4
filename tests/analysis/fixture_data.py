"""Test data for the analysis layer: real missions (run_mission) turned into DataFrames
with the columns of the results database contract, independently of the sweep's store
(so that the statistics and figures are tested on their own)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from mrcomm.run.config import make_config
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import run_mission

LF_KEYS = (
    "na_movement_time",
    "leader_movement_time",
    "follower_movement_time",
    "leader_disconnect_time",
    "follower_waiting_time",
    "role_assignment_time",
    "switching_time",
)
MISSION_KEYS = (
    "tasks_completed",
    "execution_phase_time",
    "total_movement_time",
    "total_distance",
    "near_collisions",
    "near_collisions_filtered",
    "delay_time",
    "idle_time",
    "task_execution_time",
    "min_separation",
    "max_separation",
    "timed_out",
)


@dataclass
class Frames:
    """The contract's tables as DataFrames (the shape of ``load_results``)."""

    runs: pd.DataFrame
    configs: pd.DataFrame
    robot_metrics: pd.DataFrame
    failed_tasks: pd.DataFrame
    intervals: pd.DataFrame
    events: pd.DataFrame
    rssi: pd.DataFrame
    messages: pd.DataFrame = field(default_factory=pd.DataFrame)
    links: pd.DataFrame = field(default_factory=pd.DataFrame)


def run_row(result: MissionResult, repetition: int) -> dict[str, Any]:
    cfg, m = result.config, result.mission
    config_id = cfg["label"]
    row: dict[str, Any] = {
        "run_id": f"{config_id}-r{repetition:03d}",
        "config_id": config_id,
        "experiment": "test",
        "label": cfg["label"],
        "scenario": cfg["scenario_name"],
        "network": cfg["network"],
        "spl": float(cfg["spl"]),
        "threshold": cfg["threshold"],
        "behaviour": cfg["behaviour"],
        "repetition": repetition,
        "seed": cfg["seed"],
        "mode": "sim",
        "status": "ok",
        "error": None,
        "sim_time_s": result.sim_time_s,
        "wall_time_s": result.wall_time_s,
        "successful": bool(m["successful"]),
        "n_failed_tasks": len(m["failed_tasks"]),
    }
    for key in MISSION_KEYS:
        row[key] = m.get(key)
    lf = cfg["behaviour"] == "lf"
    for key in LF_KEYS:
        row[key] = m.get(key) if lf else None
    total = result.aon.get("total", {}) if result.aon else {}
    row["aon_publications"] = total.get("publications")
    row["aon_resends"] = total.get("resend_publications")
    row["aon_max_finish_time"] = total.get("max_finish_time")
    return row


def frames_from_results(results: list[tuple[MissionResult, int]]) -> Frames:
    runs, metrics, failed, intervals, events, rssi = [], [], [], [], [], []
    for result, rep in results:
        row = run_row(result, rep)
        run_id = row["run_id"]
        runs.append(row)
        for robot, values in result.robots.items():
            for metric, value in values.items():
                if isinstance(value, bool | int | float) and value is not None:
                    metrics.append((run_id, robot, metric, float(value)))
            for task in values.get("failed_tasks", []):
                failed.append((run_id, str(task), robot))
        for robot, timeline in result.timelines.items():
            rec = timeline.to_records()
            for i in rec["intervals"]:
                intervals.append((run_id, robot, i["track"], i["label"], i["start"], i["end"]))
            for e in rec["events"]:
                data = {k: v for k, v in e.items() if k not in ("time", "label")}
                events.append((run_id, robot, e["time"], e["label"], json.dumps(data)))
        for t, src, dst, value in result.rssi_series:
            rssi.append((run_id, t, src, dst, value))
    runs_df = pd.DataFrame(runs)
    configs = runs_df[
        ["config_id", "experiment", "label", "scenario", "network", "spl", "threshold", "behaviour"]
    ].drop_duplicates()
    return Frames(
        runs=runs_df,
        configs=configs.assign(options="{}"),
        robot_metrics=pd.DataFrame(metrics, columns=["run_id", "robot", "metric", "value"]),
        failed_tasks=pd.DataFrame(failed, columns=["run_id", "task_id", "robot"]),
        intervals=pd.DataFrame(
            intervals, columns=["run_id", "robot", "track", "label", "t_start", "t_end"]
        ),
        events=pd.DataFrame(events, columns=["run_id", "robot", "t", "label", "data"]),
        rssi=pd.DataFrame(rssi, columns=["run_id", "t", "src", "dst", "rssi"]),
    )


def run_study(
    world: ScenarioResources,
    scenario: Path,
    reps: int,
    network: str = "ah",
    threshold: str = "slt",
    spls: tuple[float, ...] = (0, 50),
    behaviours: tuple[str, ...] = ("nb", "lf"),
    max_time: float = 900.0,
) -> Frames:
    """Every (behaviour, SPL) × ``reps`` seeds, run for real."""
    results = []
    for behaviour in behaviours:
        for spl in spls:
            for rep in range(reps):
                config = make_config(
                    None,
                    scenario=scenario,
                    network=network,
                    threshold=threshold,
                    behaviour=behaviour,
                    spl=spl,
                    seed=1000 + rep,
                    max_time=max_time,
                )
                results.append((run_mission(config, world), rep))
    return frames_from_results(results)
