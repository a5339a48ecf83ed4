"""``--db`` / ``--experiment`` of the commands that produce one run (``mrcomm run``,
``live``, ``collect``): check the results database before the mission (bad input fails
at once, before any work or process), store the finished run afterwards
(:mod:`mrcomm.experiment.adhoc`) and say where it went."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from mrcomm.errors import InputError
from mrcomm.output_paths import DATABASE_SUFFIXES, check_output_file

if TYPE_CHECKING:
    from mrcomm.experiment.adhoc import StoredRun
    from mrcomm.run.result import MissionResult

DbOpt = Annotated[
    Path | None,
    typer.Option(help="Also store the run in this results database (DuckDB; created if new)."),
]
KeepDuplicateOpt = Annotated[
    bool,
    typer.Option(
        "--keep-duplicate",
        help="With --db: store the run even if the same run (configuration, seed and "
        "inputs; live: the same record) is stored already.",
    ),
]
ExperimentOpt = Annotated[
    str | None,
    typer.Option(help="Experiment the run is stored under in --db (default: adhoc)."),
]


def check_db(db: Path | None, experiment: str | None) -> None:
    """Before the mission: the database must be usable (read-only check)."""
    if db is None:
        if experiment is not None:
            raise InputError("names where to store the run: add --db", field="--experiment")
        return
    from mrcomm.experiment.adhoc import DEFAULT_EXPERIMENT, check_target

    check_output_file(db, "--db", DATABASE_SUFFIXES)
    check_target(db, experiment or DEFAULT_EXPERIMENT)


def store_run(
    db: Path | None,
    experiment: str | None,
    result: MissionResult,
    *,
    live_options: dict[str, Any] | None = None,
    run_fingerprint: str | None = None,
    keep_duplicate: bool = False,
    if_lost: str = "",
) -> StoredRun | None:
    """Store the finished run in ``db`` (None: nothing to do). ``if_lost`` tells the
    user how to store it later should the database have become unusable meanwhile."""
    if db is None:
        return None
    from mrcomm.experiment.adhoc import DEFAULT_EXPERIMENT, store_result

    try:
        return store_result(
            db,
            result,
            experiment=experiment or DEFAULT_EXPERIMENT,
            live_options=live_options,
            run_fingerprint=run_fingerprint,
            keep_duplicate=keep_duplicate,
        )
    except InputError as err:
        if not if_lost:
            raise
        raise InputError(f"{err.message}; {if_lost}", file=err.file, field=err.field) from None


def stored_json(stored: StoredRun) -> dict[str, Any]:
    """The ``stored`` member of ``--json`` output."""
    return {
        "db": str(stored.db_path),
        "experiment": stored.experiment,
        "config_id": stored.config_id,
        "run_id": stored.run_id,
        "repetition": stored.repetition,
        "mode": stored.mode,
        "new": stored.new,
    }
