"""``mrcomm sweep`` (run an experiment schema into the results database, resumably, on a
local process pool or a Dask cluster) and ``mrcomm export`` (tables to CSV/Parquet).

Order of checks, so that bad input never touches the database: schema file, options,
database (read-only), scheduler; only then is the database opened for writing.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from concurrent.futures import Executor
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from mrcomm.cli.run_options import SetOpt, parse_assignments
from mrcomm.errors import InputError, Interrupted
from mrcomm.output_paths import DATABASE_SUFFIXES, check_output_dir, check_output_file

if TYPE_CHECKING:
    from mrcomm.experiment.runner import SweepPlan, SweepReport
    from mrcomm.experiment.schema import Experiment
    from mrcomm.experiment.worker import RunOutcome

#: Exit status when the sweep ended but some runs failed (bad input is 2).
EXIT_RUNS_FAILED = 1


#: Most sweep workers per CPU ``--jobs`` may ask for.
JOBS_PER_CPU = 4


def sweep(
    schema: Annotated[
        Path,
        typer.Argument(
            help="Experiment schema YAML, or a bundled experiment's name: demo, ah, wlan, "
            "baseline, ... (`mrcomm scenario list`)."
        ),
    ],
    # 100,000 below is mrcomm.experiment.schema.MAX_RUNS (not imported: --help stays
    # light; tests/cli/test_sweep_cli.py keeps the two equal).
    reps: Annotated[
        int | None,
        typer.Option(
            help="Repetitions per configuration (default: the schema's); at most 100,000 "
            "runs (configurations x repetitions) per sweep."
        ),
    ] = None,
    jobs: Annotated[
        int | None, typer.Option(help="Local worker processes (default: one per CPU).")
    ] = None,
    db: Annotated[Path, typer.Option(help="Results database (DuckDB).")] = Path("results.duckdb"),
    scheduler: Annotated[
        str | None,
        typer.Option(help="Dask scheduler, e.g. tcp://host:8786 (needs the cluster extra)."),
    ] = None,
    record: Annotated[
        Path | None, typer.Option(help="Directory for one MCAP recording per run.")
    ] = None,
    run_timeout: Annotated[
        float, typer.Option(help="Wall-clock limit of one run, s (then: status timeout).")
    ] = 900.0,
    connect_timeout: Annotated[
        float, typer.Option(help="How long to wait for the Dask scheduler, s.")
    ] = 10.0,
    sets: SetOpt = None,
) -> None:
    """Run every configuration x repetition of an experiment (resumable).

    Runs already stored as ok are skipped; failed or timed-out runs are run again.
    Results go to a DuckDB database (docs/RESULTS.md). A sweep may hold at most 100,000
    runs (configurations x repetitions, --reps included), counted before anything is
    built; split a larger study into several experiments in one database."""
    # Imported here: DuckDB and pandas are not needed by the other commands.
    # --reps goes in with the schema: the run count is checked before anything is built.
    from mrcomm.bundled import resolve
    from mrcomm.experiment.runner import (
        SweepReport,
        dask_executor,
        execute_sweep,
        plan_sweep,
        process_pool,
    )
    from mrcomm.experiment.schema import load_experiment

    schema = resolve(schema, "experiment")
    experiment = load_experiment(schema, parse_assignments(sets), repetitions=reps)
    if jobs is not None and jobs < 1:
        raise InputError(f"must be at least 1, got {jobs}", field="--jobs")
    # Each worker is a process holding a scenario and a mission (~100 MB): more than a
    # few per core only thrashes the machine.
    most = JOBS_PER_CPU * (os.cpu_count() or 1)
    if jobs is not None and jobs > most:
        raise InputError(
            f"at most {most} ({JOBS_PER_CPU} per CPU on this machine), got {jobs}", field="--jobs"
        )
    if jobs is not None and scheduler is not None:
        raise InputError("give --jobs or --scheduler, not both (the cluster sets its workers)")
    if not run_timeout > 0:
        raise InputError(f"must be positive, got {run_timeout:g}", field="--run-timeout")
    # Dask parses the timeout as text: NaN or infinity crashed it (a KeyError traceback),
    # and a negative one was reported as an unreachable scheduler.
    if not (math.isfinite(connect_timeout) and connect_timeout > 0):
        raise InputError(
            f"must be a positive number of seconds, got {connect_timeout:g}",
            field="--connect-timeout",
        )
    check_output_file(db, "--db", DATABASE_SUFFIXES)
    if record is not None:
        _check_record_dir(record)
    plan = plan_sweep(experiment, db, repetitions=reps, record_dir=record)
    if record is not None:
        _remove_partial_recordings(record, [s.run_id for s in plan.todo])
    console = Console(stderr=True)
    if not plan.todo:
        typer.echo(_summary(plan, SweepReport(len(plan.runs), plan.skipped)))
        return
    close: Callable[[], None] | None = None
    if scheduler is not None:
        executor, in_flight, close = dask_executor(scheduler, connect_timeout)
        pools: list[Executor] = [executor]
        respawn = None
    else:
        workers = jobs or os.cpu_count() or 1
        pools = [process_pool(workers)]
        in_flight = 2 * workers

        def respawn() -> Executor:
            pools.append(process_pool(workers))
            return pools[-1]

    _warn_ignored(experiment)  # every check passed: the work begins
    if record is not None:
        record.mkdir(parents=True, exist_ok=True)
    interrupted = False
    try:
        with _Display(console, plan) as display:
            report = execute_sweep(
                plan,
                pools[0],
                max_in_flight=in_flight,
                run_timeout=run_timeout,
                record_dir=record,
                on_outcome=display.update,
                respawn=respawn,
            )
    except KeyboardInterrupt:
        interrupted = True
    finally:
        for pool in pools:
            pool.shutdown(wait=not interrupted, cancel_futures=True)
        if close is not None:
            close()
    if interrupted:
        raise Interrupted(
            f"interrupted; finished runs are stored in {db}: run the same command again to resume"
        )
    typer.echo(_summary(plan, report))
    for run_id, status, message in report.failures[:10]:
        typer.echo(f"  {status}: {run_id}: {message}")
    if len(report.failures) > 10:
        typer.echo(f"  ... and {len(report.failures) - 10} more (see the runs table)")
    if report.failed or report.not_run:
        raise typer.Exit(EXIT_RUNS_FAILED)


def export(
    out: Annotated[Path, typer.Option(help="Output directory (one file per table).")],
    db: Annotated[Path, typer.Option(help="Results database (DuckDB).")] = Path("results.duckdb"),
    fmt: Annotated[str, typer.Option("--format", help="csv | parquet.")] = "csv",
) -> None:
    """Export every results table to CSV or Parquet files."""
    from mrcomm.experiment.export import check_format, export_tables

    check_format(fmt)
    check_output_dir(out, "--out")
    written = export_tables(db, fmt, out)
    typer.echo(f"wrote {len(written)} tables to {out}: {', '.join(p.name for p in written)}")


def _warn_ignored(experiment: Experiment) -> None:
    """One line per kind of setting that changes nothing, with how many configurations
    have it (e.g. NB runs under several thresholds: identical runs)."""
    counts: dict[str, list[str]] = {}
    for configuration in experiment.configurations:
        for warning in configuration.config.ignored_settings():
            counts.setdefault(warning.split(" (")[0], []).append(configuration.label)
    for what, labels in counts.items():
        typer.echo(
            f"mrcomm: warning: {what} in {len(labels)} configuration(s) "
            f"({', '.join(labels[:4])}{', ...' if len(labels) > 4 else ''}): their runs "
            "differ from those without a threshold only in link statistics; drop them "
            "with an 'exclude' entry if they are not wanted",
            err=True,
        )


def _remove_partial_recordings(record: Path, run_ids: list[str]) -> None:
    """Remove what a killed sweep left of the recordings of the runs this one will redo
    (a recording is written to ``.<run>.mcap.<random>.tmp`` and renamed when complete;
    a sweep killed outright cannot remove it; the database's lock makes these runs
    this sweep's)."""
    for run_id in run_ids:
        for partial in record.glob(f".{run_id}.mcap.*.tmp"):
            partial.unlink(missing_ok=True)


def _check_record_dir(record: Path) -> None:
    check_output_dir(record, "--record")
    try:
        from mrcomm.experiment import recording  # noqa: F401
    except ImportError as err:
        raise InputError(f"recordings are not available ({err})", field="--record") from None


def _summary(plan: SweepPlan, report: SweepReport) -> str:
    exp = plan.experiment
    n_configs = len(exp.configurations)
    reps = len(plan.runs) // max(n_configs, 1)
    text = (
        f"{exp.name}: {len(plan.runs)} runs ({n_configs} configurations x {reps} "
        f"repetitions): {report.ok} new ok, {report.failed} failed, "
        f"{plan.skipped} already done"
    )
    if report.not_run:
        text += f", {report.not_run} not run (executor broke)"
    if report.done:
        text += f"; {report.wall_time_s:.1f} s"
    return f"{text}; results in {plan.db_path}"


class _Display:
    """Progress: a rich bar (runs done/total, failures, ETA) on a terminal; one plain
    line per finished run otherwise (batch logs, pipes)."""

    def __init__(self, console: Console, plan: SweepPlan) -> None:
        self.total = len(plan.todo)
        self.done = 0
        self.failed = 0
        self.live = console.is_terminal
        self.progress = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("[red]{task.fields[failed]} failed"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=console,
            disable=not self.live,
        )
        self.task: TaskID | None = None
        self.name = plan.experiment.name

    def __enter__(self) -> _Display:
        self.progress.start()
        self.task = self.progress.add_task(self.name, total=self.total, failed=0)
        return self

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()

    def update(self, outcome: RunOutcome) -> None:
        self.done += 1
        if outcome.status != "ok":
            self.failed += 1
        if self.task is not None:
            self.progress.update(self.task, advance=1, failed=self.failed)
        if not self.live:
            note = f": {outcome.message}" if outcome.message else ""
            typer.echo(
                f"[{self.done}/{self.total}] {outcome.status} {outcome.run_id} "
                f"({outcome.wall_time_s:.1f} s){note}"
            )
