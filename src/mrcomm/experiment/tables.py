"""The results database contract: table names, columns and SQL types (docs/RESULTS.md).

Pure data, no database import: the worker processes use the column orders to build
their rows, the parent (:mod:`mrcomm.experiment.store`) creates and fills the tables.
Every per-run table is keyed by ``run_id = f"{config_id}-r{repetition:03d}"``.
"""

from __future__ import annotations

#: Bumped whenever a table or column changes meaning; a database written with another
#: version is refused before it is touched, except one that :data:`UPGRADES` extends.
SCHEMA_VERSION = "7"

Columns = tuple[tuple[str, str], ...]

#: Values of ``runs.mode``: a simulated run, or a live one (every agent its own process).
RUN_MODES = ("sim", "live")

META: Columns = (("key", "TEXT PRIMARY KEY"), ("value", "TEXT"))

#: One row per experiment ever swept into the database (several may share one file).
EXPERIMENTS: Columns = (
    ("experiment", "TEXT PRIMARY KEY"),
    ("base_seed", "BIGINT"),
    ("schema_path", "TEXT"),
    ("schema_yaml", "TEXT"),
    ("updated", "TIMESTAMP"),
)

CONFIGS: Columns = (
    ("config_id", "TEXT PRIMARY KEY"),
    ("experiment", "TEXT"),
    ("label", "TEXT"),
    ("scenario", "TEXT"),
    ("network", "TEXT"),
    ("spl", "DOUBLE"),
    ("threshold", "TEXT"),
    ("behaviour", "TEXT"),
    ("options", "JSON"),
)

#: Configuration columns repeated in ``runs`` so that one table answers most questions.
RUN_CONFIG_COLUMNS: Columns = (
    ("run_id", "TEXT PRIMARY KEY"),
    ("config_id", "TEXT"),
    ("experiment", "TEXT"),
    ("label", "TEXT"),
    ("scenario", "TEXT"),
    ("network", "TEXT"),
    ("spl", "DOUBLE"),
    ("threshold", "TEXT"),
    ("behaviour", "TEXT"),
    ("repetition", "INTEGER"),
    ("seed", "BIGINT"),
    ("mode", "TEXT"),
    ("status", "TEXT"),
    ("error", "TEXT"),
    ("sim_time_s", "DOUBLE"),
    ("wall_time_s", "DOUBLE"),
)

#: Mission metrics of ``runs``: (column, SQL type, key in MissionResult.mission).
RUN_METRIC_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("successful", "BOOLEAN", "successful"),
    ("n_failed_tasks", "INTEGER", "failed_tasks"),
    ("tasks_completed", "INTEGER", "tasks_completed"),
    ("execution_phase_time", "DOUBLE", "execution_phase_time"),
    ("total_movement_time", "DOUBLE", "total_movement_time"),
    ("total_distance", "DOUBLE", "total_distance"),
    ("near_collisions", "INTEGER", "near_collisions"),
    ("near_collisions_filtered", "INTEGER", "near_collisions_filtered"),
    ("near_collisions_confirmed", "INTEGER", "near_collisions_confirmed"),
    ("near_collisions_false", "INTEGER", "near_collisions_false"),
    ("near_collisions_missed", "INTEGER", "near_collisions_missed"),
    ("delay_time", "DOUBLE", "delay_time"),
    ("idle_time", "DOUBLE", "idle_time"),
    ("task_execution_time", "DOUBLE", "task_execution_time"),
    ("min_separation", "DOUBLE", "min_separation"),
    ("max_separation", "DOUBLE", "max_separation"),
    ("timed_out", "BOOLEAN", "timed_out"),
    # The team as a whole (large teams).
    ("tasks_per_minute", "DOUBLE", "tasks_per_minute"),
    ("assigner_connected", "DOUBLE", "assigner_connected"),
    ("largest_group_mean", "DOUBLE", "largest_group_mean"),
    ("largest_group_min", "DOUBLE", "largest_group_min"),
    # Leader-Follower totals: NULL for behaviours without roles.
    ("na_movement_time", "DOUBLE", "na_movement_time"),
    ("leader_movement_time", "DOUBLE", "leader_movement_time"),
    ("follower_movement_time", "DOUBLE", "follower_movement_time"),
    ("leader_disconnect_time", "DOUBLE", "leader_disconnect_time"),
    ("follower_waiting_time", "DOUBLE", "follower_waiting_time"),
    ("role_assignment_time", "DOUBLE", "role_assignment_time"),
    ("switching_time", "DOUBLE", "switching_time"),
)


#: AON totals of ``runs`` (NULL when statuses go without AON): (column, type, key).
RUN_AON_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("aon_publications", "INTEGER", "publications"),
    ("aon_resends", "INTEGER", "resend_publications"),
    ("aon_max_finish_time", "DOUBLE", "max_finish_time"),
)

#: Where a run came from (mrcomm.run.provenance): the software, the inputs, the machine,
#: and the fingerprint (configuration id, seed, input hashes; for a live run: its
#: record) that makes storing the same run twice detectable.
RUN_PROVENANCE_COLUMNS: Columns = (
    ("mrcomm_version", "TEXT"),
    ("git_commit", "TEXT"),
    ("machine", "TEXT"),
    ("input_hashes", "JSON"),
    ("fingerprint", "TEXT"),
)

RUNS: Columns = (
    *RUN_CONFIG_COLUMNS,
    *((c, t) for c, t, _ in RUN_METRIC_COLUMNS),
    *((c, t) for c, t, _ in RUN_AON_COLUMNS),
    ("finished_at", "TIMESTAMP"),
    *RUN_PROVENANCE_COLUMNS,
)

#: The team metrics a behaviour's spec adds that have no column of ``runs`` (every
#: behaviour but LF, whose totals are the original study's and have columns): one row
#: per run and metric. Loading results puts each as a column of the runs frame.
TEAM_METRICS: Columns = (
    ("run_id", "TEXT"),
    ("metric", "TEXT"),
    ("value", "DOUBLE"),
)

ROBOT_METRICS: Columns = (
    ("run_id", "TEXT"),
    ("robot", "TEXT"),
    ("metric", "TEXT"),
    ("value", "DOUBLE"),
)
FAILED_TASKS: Columns = (("run_id", "TEXT"), ("task_id", "TEXT"), ("robot", "TEXT"))
MESSAGES: Columns = (
    ("run_id", "TEXT"),
    ("agent", "TEXT"),
    ("topic", "TEXT"),
    ("sent", "INTEGER"),
    ("received", "INTEGER"),
    ("dropped_loss", "INTEGER"),
    ("dropped_range", "INTEGER"),
    ("dropped_radio", "INTEGER"),
    ("dropped_queue", "INTEGER"),
    ("delay_mean_s", "DOUBLE"),
    ("delay_max_s", "DOUBLE"),
    # The shared channel's (NULL without it): collisions at the agent, and the seconds
    # its own messages on the topic took on the air.
    ("dropped_collision", "INTEGER"),
    ("airtime_s", "DOUBLE"),
)
LINKS: Columns = (
    ("run_id", "TEXT"),
    ("src", "TEXT"),
    ("dst", "TEXT"),
    ("min_distance", "DOUBLE"),
    ("max_distance", "DOUBLE"),
    ("min_rssi", "DOUBLE"),
    ("time_in_warning", "DOUBLE"),
    ("warnings", "INTEGER"),
    ("time_disconnected", "DOUBLE"),
)
INTERVALS: Columns = (
    ("run_id", "TEXT"),
    ("robot", "TEXT"),
    ("track", "TEXT"),
    ("label", "TEXT"),
    ("t_start", "DOUBLE"),
    ("t_end", "DOUBLE"),
)
EVENTS: Columns = (
    ("run_id", "TEXT"),
    ("robot", "TEXT"),
    ("t", "DOUBLE"),
    ("label", "TEXT"),
    ("data", "JSON"),
)
RSSI: Columns = (
    ("run_id", "TEXT"),
    ("t", "DOUBLE"),
    ("src", "TEXT"),
    ("dst", "TEXT"),
    ("rssi", "DOUBLE"),
)

#: When each robot pair's link was in warning or out of range (connected otherwise).
LINK_STATES: Columns = (
    ("run_id", "TEXT"),
    ("robot_a", "TEXT"),
    ("robot_b", "TEXT"),
    ("state", "TEXT"),
    ("t_start", "DOUBLE"),
    ("t_end", "DOUBLE"),
)
#: Every robot's position, sampled every TRAJECTORY_STORE_PERIOD simulated s.
TRAJECTORIES: Columns = (
    ("run_id", "TEXT"),
    ("robot", "TEXT"),
    ("t", "DOUBLE"),
    ("x", "DOUBLE"),
    ("y", "DOUBLE"),
)
TRAJECTORY_STORE_PERIOD = 1.0

#: Tables written once per run, in one transaction (``runs`` first).
RUN_TABLES: dict[str, Columns] = {
    "runs": RUNS,
    "team_metrics": TEAM_METRICS,
    "robot_metrics": ROBOT_METRICS,
    "failed_tasks": FAILED_TASKS,
    "messages": MESSAGES,
    "links": LINKS,
    "intervals": INTERVALS,
    "events": EVENTS,
    "rssi": RSSI,
    "link_states": LINK_STATES,
    "trajectories": TRAJECTORIES,
}

#: Every table, in creation order.
TABLES: dict[str, Columns] = {
    "meta": META,
    "experiments": EXPERIMENTS,
    "configs": CONFIGS,
    **RUN_TABLES,
}


def column_names(table: str) -> tuple[str, ...]:
    return tuple(name for name, _ in TABLES[table])


def create_statement(table: str) -> str:
    columns = ", ".join(f"{name} {sql_type}" for name, sql_type in TABLES[table])
    return f"CREATE TABLE IF NOT EXISTS {table} ({columns})"


#: Older schema versions this one only adds columns to (at the end of their tables): a
#: database of such a version is read as it is (the added columns read as missing) and
#: upgraded in place when opened for writing.
UPGRADES: dict[str, dict[str, Columns]] = {
    "6": {"messages": (("dropped_collision", "INTEGER"), ("airtime_s", "DOUBLE"))},
}
