"""Notebook API: a sweep's results as pandas DataFrames in one call.

    from mrcomm.experiment.api import load_results
    res = load_results("results.duckdb")
    res.runs.groupby("label").execution_phase_time.mean()
    res.con.sql("SELECT label, avg(total_distance) FROM runs GROUP BY label").df()
    live = load_results("results.duckdb", mode="live")  # only the live runs

The database is opened read-only (several notebooks may read while no sweep writes).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import duckdb
import pandas as pd

from mrcomm.experiment.store import damaged, open_readonly
from mrcomm.experiment.tables import RUN_TABLES

_ORDER = {
    "runs": "experiment, label, repetition",
    "configs": "experiment, label",
    "team_metrics": "run_id, metric",
    "robot_metrics": "run_id, robot, metric",
    "failed_tasks": "run_id, task_id",
    "messages": "run_id, agent, topic",
    "links": "run_id, src, dst",
    "intervals": "run_id, robot, track, t_start",
    "events": "run_id, robot, t",
    "rssi": "run_id, t, src, dst",
    "link_states": "run_id, t_start, robot_a, robot_b",
    "trajectories": "run_id, robot, t",
}


@dataclass
class Results:
    """Every results table as a DataFrame (tidy, long form), plus the connection."""

    #: One row per run; a behaviour's team metrics (``team_metrics``) as columns too.
    runs: pd.DataFrame
    configs: pd.DataFrame
    team_metrics: pd.DataFrame
    robot_metrics: pd.DataFrame
    failed_tasks: pd.DataFrame
    messages: pd.DataFrame
    links: pd.DataFrame
    intervals: pd.DataFrame
    events: pd.DataFrame
    rssi: pd.DataFrame
    link_states: pd.DataFrame
    trajectories: pd.DataFrame
    #: Read-only DuckDB connection for raw SQL.
    con: duckdb.DuckDBPyConnection

    @property
    def ok_runs(self) -> pd.DataFrame:
        """Runs that finished (status 'ok'; the mission itself may still have failed)."""
        return self.runs[self.runs["status"] == "ok"]

    def close(self) -> None:
        self.con.close()


def load_results(
    db_path: str | Path, experiment: str | None = None, mode: str | None = None
) -> Results:
    """Load every table of the results database at ``db_path``: every run, simulated
    and live alike (the ``mode`` column tells them apart), or only those of one
    experiment and/or one mode ('sim' | 'live'). Raises InputError for a missing or
    incompatible file."""
    con = open_readonly(Path(db_path))
    # Filters apply to the runs table; every other table follows its runs.
    filters = {k: v for k, v in (("experiment", experiment), ("mode", mode)) if v is not None}
    condition = " AND ".join(f"runs.{k} = ?" for k in filters)
    params = list(filters.values())
    frames: dict[str, pd.DataFrame] = {}
    for table in ("configs", *RUN_TABLES):
        if not filters:
            query = f"SELECT * FROM {table}"
        elif table == "runs":
            query = f"SELECT * FROM runs WHERE {condition}"
        elif table == "configs" and mode is None:
            # Every configuration of the experiment, run or not (yet).
            query = "SELECT * FROM configs WHERE experiment = ?"
        elif table == "configs":
            query = (
                "SELECT * FROM configs WHERE config_id IN "
                f"(SELECT config_id FROM runs WHERE {condition})"
            )
        else:
            query = f"SELECT x.* FROM {table} x JOIN runs USING (run_id) WHERE {condition}"
        try:
            frames[table] = con.execute(f"{query} ORDER BY {_ORDER[table]}", params).df()
        except duckdb.Error as err:  # a file damaged past its first pages
            con.close()
            raise damaged(Path(db_path), err) from None
    frames["runs"] = with_team_metrics(frames["runs"], frames["team_metrics"])
    return Results(con=con, **frames)


def with_team_metrics(runs: pd.DataFrame, team_metrics: pd.DataFrame) -> pd.DataFrame:
    """``runs`` with a column per team metric a behaviour added (NULL for the runs of
    other behaviours), so that every metric is a column of the runs frame."""
    if team_metrics.empty:
        return runs
    wide = team_metrics.pivot_table(
        index="run_id", columns="metric", values="value", aggfunc="first", dropna=False
    )
    wide.columns = [str(c) for c in wide.columns]
    new = [c for c in wide.columns if c not in runs.columns]
    return runs.merge(wide[new], how="left", left_on="run_id", right_index=True)
