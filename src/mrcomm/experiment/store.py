"""The results database (DuckDB): compatibility checks, creation, and writing runs.

* :func:`inspect_database` opens an existing file **read-only** and refuses it (one-line
  :class:`~mrcomm.errors.InputError`) when it is not a DuckDB file, not an MRComm
  results database, of another schema version, or locked by another process — before
  anything writes to it.
* :class:`ResultStore` is the writer: a sweep's parent process, or a command storing
  one ad-hoc run (``adhoc.py``); DuckDB's file lock keeps it to one at a time.
  Each finished run is written in ONE transaction covering all its tables, so a sweep
  killed at any moment (even SIGKILL) leaves whole runs or nothing: DuckDB's write-ahead
  log drops an uncommitted transaction on the next open.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import json
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

import duckdb

from mrcomm.errors import InputError, MissionFailed
from mrcomm.experiment.rows import Rows, check_rows
from mrcomm.experiment.schema import Experiment
from mrcomm.experiment.tables import (
    RUN_TABLES,
    SCHEMA_VERSION,
    TABLES,
    UPGRADES,
    create_statement,
)

if TYPE_CHECKING:
    import pandas as pd

_DTYPES = {
    "DOUBLE": "float64",
    "INTEGER": "Int64",
    "BIGINT": "Int64",
    "BOOLEAN": "boolean",
    "TIMESTAMP": "datetime64[us]",
}


@dataclass
class DatabaseInfo:
    """What an existing results database already holds (empty for a new one)."""

    exists: bool
    #: experiment -> base seed
    experiments: dict[str, int] = field(default_factory=dict)
    #: experiment -> where it came from (the schema file, or ``adhoc.ADHOC_SOURCE``)
    sources: dict[str, str] = field(default_factory=dict)
    #: config_id -> (experiment, label)
    configs: dict[str, tuple[str, str]] = field(default_factory=dict)
    #: run_id -> status
    runs: dict[str, str] = field(default_factory=dict)


def _connect(path: Path, *, read_only: bool) -> duckdb.DuckDBPyConnection:
    try:
        # No progress bar: DuckDB draws one on stdout for queries over 2 s, into the
        # CSV or JSON a command prints (and into a notebook's output).
        con = duckdb.connect(str(path), read_only=read_only)
        con.execute("SET enable_progress_bar = false")
        return con
    except duckdb.Error as err:
        # DuckDB says "Could not set lock on file ... Conflicting lock is held" when
        # another process has it open; anything else is a file it cannot read.
        if "conflicting lock" in str(err).lower():
            raise InputError(
                "database is in use by another process (a sweep still running?)", file=path
            ) from None
        raise damaged(path, err) from None


def damaged(path: Path, err: BaseException) -> InputError:
    """The one-line error for a database DuckDB cannot read (truncated, overwritten,
    not a database at all), with the first line of DuckDB's own message."""
    text = str(err).strip()
    first = text.splitlines()[0] if text else type(err).__name__
    return InputError(f"damaged or not a DuckDB database ({first})", file=path)


def _check_version(con: duckdb.DuckDBPyConnection, path: Path, *, upgrade: bool = False) -> bool:
    """True for an MRComm results database of this version (or one it extends, upgraded
    in place when ``upgrade``); False for an empty file. Raise InputError for anything
    else (a damaged file too)."""
    try:
        return _read_version(con, path, upgrade)
    except duckdb.Error as err:
        raise damaged(path, err) from None


def _read_version(con: duckdb.DuckDBPyConnection, path: Path, upgrade: bool) -> bool:
    tables = {row[0] for row in con.execute("SELECT table_name FROM duckdb_tables()").fetchall()}
    if not tables:
        return False
    if "meta" not in tables:
        raise InputError("not an MRComm results database (no 'meta' table)", file=path)
    row = con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
    version = row[0] if row else None
    added = UPGRADES.get(version, {}) if isinstance(version, str) else {}
    if version != SCHEMA_VERSION and not added:
        raise InputError(
            f"results schema version {version!r}, this mrcomm uses version "
            f"{SCHEMA_VERSION!r}; use a new --db (or the mrcomm that wrote it)",
            file=path,
        )
    missing = sorted(set(TABLES) - tables)
    if missing:
        raise InputError(f"damaged results database: table '{missing[0]}' is missing", file=path)
    for table, columns in TABLES.items():
        have = [row[0] for row in con.execute(f"DESCRIBE {table}").fetchall()]
        new = {name for name, _ in added.get(table, ())}
        if have != [name for name, _ in columns if name not in new]:
            raise InputError(
                f"table '{table}' has other columns than this mrcomm writes (a database "
                "of another development version?); use a new --db",
                file=path,
            )
    if added and upgrade:
        con.execute("BEGIN TRANSACTION")
        for table, columns in added.items():
            for name, sql_type in columns:
                con.execute(f"ALTER TABLE {table} ADD COLUMN {name} {sql_type}")
        con.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'", [SCHEMA_VERSION])
        con.execute("COMMIT")
    return True


def open_readonly(path: Path) -> duckdb.DuckDBPyConnection:
    """A read-only connection to a results database of this schema version."""
    path = Path(path)
    if not path.is_file():
        raise InputError("database not found", file=path)
    con = _connect(path, read_only=True)
    try:
        if not _check_version(con, path):
            raise InputError("empty database: no results yet", file=path)
    except BaseException:
        con.close()
        raise
    return con


def inspect_database(path: Path) -> DatabaseInfo:
    """Check an existing database read-only (never modifies the file)."""
    path = Path(path)
    if not path.exists():
        return DatabaseInfo(exists=False)
    if not path.is_file():
        raise InputError("not a file", file=path)
    con = _connect(path, read_only=True)
    try:
        if not _check_version(con, path):
            return DatabaseInfo(exists=True)
        experiments = con.execute(
            "SELECT experiment, base_seed, schema_path FROM experiments"
        ).fetchall()
        return DatabaseInfo(
            exists=True,
            experiments={name: seed for name, seed, _ in experiments},
            sources={name: source for name, _, source in experiments},
            configs={
                cid: (exp, label)
                for cid, exp, label in con.execute(
                    "SELECT config_id, experiment, label FROM configs"
                ).fetchall()
            },
            runs=dict(con.execute("SELECT run_id, status FROM runs").fetchall()),
        )
    finally:
        con.close()


def _frame(table: str, rows: list[tuple[Any, ...]]) -> pd.DataFrame:
    """Rows as a DataFrame with one explicit dtype per SQL type (None -> NULL).

    Built column by column with the dtype given up front: several times faster than
    ``from_records`` + ``astype``, and the parent writes every run of the sweep.
    """
    # Imported here: checking a database (before a mission) must not pay for pandas.
    import pandas as pd

    columns = list(zip(*rows, strict=True)) if rows else [()] * len(TABLES[table])
    return pd.DataFrame(
        {
            name: pd.Series(values, dtype=_DTYPES.get(sql_type.split()[0], object))
            for (name, sql_type), values in zip(TABLES[table], columns, strict=True)
        }
    )


def _version() -> str:
    try:
        return metadata.version("mrcomm")
    except metadata.PackageNotFoundError:
        return "unknown"


def _now() -> dt.datetime:
    # Naive UTC: DuckDB TIMESTAMP has no zone; docs/RESULTS.md says UTC.
    return dt.datetime.now(dt.UTC).replace(tzinfo=None)


class ResultStore:
    """The single writer of a results database."""

    def __init__(self, con: duckdb.DuckDBPyConnection, path: Path) -> None:
        self.con = con
        self.path = path

    @classmethod
    def open(cls, path: Path) -> ResultStore:
        """Open (creating if needed) a database that :func:`inspect_database` accepted."""
        path = Path(path)
        con = _connect(path, read_only=False)
        try:
            if not _check_version(con, path, upgrade=True):
                con.execute("BEGIN TRANSACTION")
                for table in TABLES:
                    con.execute(create_statement(table))
                con.executemany(
                    "INSERT INTO meta VALUES (?, ?)",
                    [
                        ("schema_version", SCHEMA_VERSION),
                        ("mrcomm_version", _version()),
                        ("created", _now().isoformat(timespec="seconds")),
                    ],
                )
                con.execute("COMMIT")
        except BaseException:
            con.close()
            raise
        return cls(con, path)

    def register(self, experiment: Experiment) -> None:
        """Record a swept experiment and its configurations (one transaction); it
        becomes the database's latest sweep (``meta``)."""
        con = self.con
        con.execute("BEGIN TRANSACTION")
        try:
            con.executemany(
                "INSERT OR REPLACE INTO meta VALUES (?, ?)",
                [
                    ("experiment", experiment.name),
                    ("schema_yaml", experiment.yaml_text),
                    ("mrcomm_version", _version()),
                ],
            )
            self._register(experiment)
            con.execute("COMMIT")
        except duckdb.Error as err:
            with contextlib.suppress(duckdb.Error):
                con.execute("ROLLBACK")
            raise MissionFailed(f"cannot write to {self.path}: {_cause(err)}") from None
        except BaseException:
            con.execute("ROLLBACK")
            raise

    def _register(self, experiment: Experiment) -> None:
        """The experiment's row and its new configurations (inside a transaction)."""
        con = self.con
        con.execute(
            "INSERT OR REPLACE INTO experiments VALUES (?, ?, ?, ?, ?)",
            [
                experiment.name,
                experiment.base_seed,
                str(experiment.path),
                experiment.yaml_text,
                _now(),
            ],
        )
        rows = [
            (
                c.config_id,
                c.experiment,
                c.label,
                c.scenario_name,
                c.config.network,
                float(c.config.spl),
                c.config.threshold,
                c.config.behaviour,
                json.dumps(
                    {
                        **c.config.model_dump(mode="json", exclude={"seed"}),
                        "variants": c.config.variants(),
                        **c.extra_options,
                    },
                    sort_keys=True,
                ),
            )
            for c in experiment.configurations
        ]
        frame = _frame("configs", rows)
        con.register("_new_configs", frame)
        con.execute(
            "INSERT INTO configs SELECT * FROM _new_configs "
            "WHERE config_id NOT IN (SELECT config_id FROM configs)"
        )
        con.unregister("_new_configs")

    def write_run(
        self, rows: Rows, *, replace: bool = False, experiment: Experiment | None = None
    ) -> None:
        """Write one run (every table) in one transaction; ``replace`` deletes an
        earlier attempt of the same run first (a failed run being re-run);
        ``experiment`` is registered in the same transaction (an ad-hoc run: its
        experiment, configuration and rows appear together or not at all)."""
        import pandas as pd  # see _frame

        check_rows(rows)
        run_id = rows["runs"][0][0]
        con = self.con
        con.execute("BEGIN TRANSACTION")
        try:
            if experiment is not None:
                self._register(experiment)
            if replace:
                for table in RUN_TABLES:
                    con.execute(f"DELETE FROM {table} WHERE run_id = ?", [run_id])
            for table in RUN_TABLES:
                table_rows = rows.get(table)
                if not table_rows:
                    continue
                new_rows = _frame(table, table_rows)
                if table == "runs":
                    new_rows["finished_at"] = pd.Series(
                        [_now()] * len(new_rows), dtype="datetime64[us]"
                    )
                # DuckDB scans the local DataFrame by name (a replacement scan): one
                # statement instead of register / insert / unregister.
                con.execute(f"INSERT INTO {table} SELECT * FROM new_rows")
            con.execute("COMMIT")
        except duckdb.Error as err:
            # Storage failing (a full disk, a file gone) stops a sweep: more runs would
            # fail the same way. (ROLLBACK can fail then too: the first cause is named.)
            with contextlib.suppress(duckdb.Error):
                con.execute("ROLLBACK")
            raise MissionFailed(
                f"cannot store run {run_id} in {self.path}: {_cause(err)}; nothing of it "
                "was kept, the runs stored before it are (run the same command again to "
                "go on)"
            ) from None
        except BaseException:
            con.execute("ROLLBACK")
            raise

    def next_repetition(self, config_id: str) -> int:
        """The first repetition number after every stored run of ``config_id``."""
        row = self.con.execute(
            "SELECT max(repetition) FROM runs WHERE config_id = ?", [config_id]
        ).fetchone()
        return int(row[0]) + 1 if row and row[0] is not None else 1

    def run_with_fingerprint(self, fingerprint: str) -> tuple[str, int] | None:
        """(run_id, repetition) of a finished run stored with ``fingerprint``."""
        row = self.con.execute(
            "SELECT run_id, repetition FROM runs WHERE fingerprint = ? AND status = 'ok' "
            "ORDER BY run_id LIMIT 1",
            [fingerprint],
        ).fetchone()
        return None if row is None else (str(row[0]), int(row[1]))

    def experiment_yaml(self, name: str) -> str | None:
        """The ``schema_yaml`` stored for experiment ``name`` (None: not registered)."""
        row = self.con.execute(
            "SELECT schema_yaml FROM experiments WHERE experiment = ?", [name]
        ).fetchone()
        return None if row is None else str(row[0])

    def close(self) -> None:
        self.con.close()


def _cause(err: BaseException) -> str:
    """The first line of a DuckDB error, without its type's prefix."""
    text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    return text.split(": ", 1)[1] if text.startswith(("IO Error", "TransactionContext")) else text
