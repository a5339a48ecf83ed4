"""Sweep runner: plan what is left to do, send runs to any executor, store each result.

* :func:`plan_sweep` reads the database read-only and decides which runs are left:
  every run whose ``runs`` row is missing or not ``ok`` (failed and timed-out runs are
  run again), plus, with a recording directory, ``ok`` runs whose recording is missing.
  It refuses a database whose experiment of the same name was swept with a different
  definition (same label, other configuration), or holds ad-hoc runs (``adhoc.py``), so
  results never mix.
* :func:`execute_sweep` sends the runs to a ``concurrent.futures.Executor`` (a local
  process pool, or a Dask client's executor for a cluster), keeping a bounded number in
  flight, and writes each outcome as it arrives — in the parent process only, one
  transaction per run. A worker process that dies takes the runs in flight with it;
  the pool is rebuilt and they are retried once, then recorded as errors.
"""

from __future__ import annotations

import multiprocessing
import os
import time
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, BrokenExecutor, Executor, Future, wait
from concurrent.futures.process import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from mrcomm.errors import InputError
from mrcomm.experiment.adhoc import ADHOC_SOURCE
from mrcomm.experiment.schema import Experiment, RunSpec
from mrcomm.experiment.store import ResultStore, inspect_database
from mrcomm.experiment.worker import RunOutcome, RunTask, failed_outcome, run_one, start_worker

#: Times a run may be in flight when a worker process dies before it counts as failed.
MAX_STRIKES = 2

RunFn = Callable[[RunTask], RunOutcome]


@dataclass(frozen=True)
class SweepPlan:
    experiment: Experiment
    db_path: Path
    runs: tuple[RunSpec, ...]
    todo: tuple[RunSpec, ...]
    #: Runs that already have a row (an earlier failure) to be replaced.
    replace: frozenset[str]

    @property
    def skipped(self) -> int:
        return len(self.runs) - len(self.todo)


@dataclass
class SweepReport:
    total: int
    skipped: int
    ok: int = 0
    failed: int = 0
    wall_time_s: float = 0.0
    #: (run_id, status, first line of the error) of every failed run.
    failures: list[tuple[str, str, str]] = field(default_factory=list)
    #: Runs left undone because the executor broke (and could not be rebuilt).
    not_run: int = 0

    @property
    def done(self) -> int:
        return self.ok + self.failed


def recording_path(record_dir: Path, run_id: str) -> Path:
    return record_dir / f"{run_id}.mcap"


def plan_sweep(
    experiment: Experiment,
    db_path: Path,
    *,
    repetitions: int | None = None,
    record_dir: Path | None = None,
) -> SweepPlan:
    """Decide what to run; reads the database read-only (InputError if incompatible)."""
    if repetitions is not None and repetitions < 1:
        raise InputError(f"must be at least 1, got {repetitions}", field="--reps")
    info = inspect_database(db_path)
    if info.sources.get(experiment.name) == ADHOC_SOURCE:
        raise InputError(
            f"experiment '{experiment.name}' in this database holds ad-hoc runs (mrcomm "
            "run/live --db); give the schema another name",
            file=db_path,
        )
    seed = info.experiments.get(experiment.name)
    if seed is not None and seed != experiment.base_seed:
        raise InputError(
            f"experiment '{experiment.name}' in this database has base_seed {seed}, the "
            f"schema says {experiment.base_seed}; use another --db or experiment name",
            file=db_path,
        )
    held = {label: cid for cid, (exp, label) in info.configs.items() if exp == experiment.name}
    for c in experiment.configurations:
        if c.label in held and held[c.label] != c.config_id:
            raise InputError(
                f"experiment '{experiment.name}' in this database has a different "
                f"configuration {c.label} (options changed?); use another --db or "
                "experiment name",
                file=db_path,
            )
    runs = tuple(experiment.runs(repetitions))
    todo = []
    for spec in runs:
        status = info.runs.get(spec.run_id)
        missing_recording = record_dir is not None and not (
            recording_path(record_dir, spec.run_id).is_file()
        )
        if status != "ok" or missing_recording:
            todo.append(spec)
    replace = frozenset(s.run_id for s in todo if s.run_id in info.runs)
    return SweepPlan(experiment, Path(db_path), runs, tuple(todo), replace)


def process_pool(jobs: int) -> ProcessPoolExecutor:
    """The local executor: ``jobs`` worker processes that ignore Ctrl-C and end with
    this process (:func:`~mrcomm.experiment.worker.start_worker`).

    forkserver, not fork: the parent has threads (progress bar, DuckDB), and forking a
    threaded process can deadlock the child.
    """
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    return ProcessPoolExecutor(
        max_workers=jobs, mp_context=context, initializer=start_worker, initargs=(os.getpid(),)
    )


def dask_executor(
    address: str, timeout_s: float = 10.0
) -> tuple[Executor, int, Callable[[], None]]:
    """(executor, runs to keep in flight, close) for the Dask scheduler at ``address``."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise InputError(
            "needs dask.distributed: pip install 'mrcomm[cluster]'", field="--scheduler"
        ) from None
    try:
        client = Client(address, timeout=f"{timeout_s}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as err:
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise InputError(
            f"cannot reach the Dask scheduler {address} ({first})", field="--scheduler"
        ) from None
    threads = sum(client.nthreads().values()) or 1
    # pure=False: a re-run of a failed run must really run again, not hit Dask's cache.
    return client.get_executor(pure=False), 2 * threads, client.close


def execute_sweep(
    plan: SweepPlan,
    executor: Executor,
    *,
    max_in_flight: int,
    run_timeout: float | None = None,
    record_dir: Path | None = None,
    on_outcome: Callable[[RunOutcome], None] | None = None,
    respawn: Callable[[], Executor] | None = None,
    run_fn: RunFn = run_one,
) -> SweepReport:
    """Run what ``plan`` left to do on ``executor`` and store every outcome.

    ``respawn`` builds a fresh executor when ``executor`` breaks (a worker process
    died); without it a broken executor ends the sweep, leaving the rest for the next
    sweep (``report.not_run``). KeyboardInterrupt goes through; what was written stays.
    """
    store = ResultStore.open(plan.db_path)
    try:
        store.register(plan.experiment)
        tasks = [
            RunTask(
                spec,
                timeout_s=run_timeout,
                record_path=(
                    str(recording_path(record_dir, spec.run_id)) if record_dir is not None else None
                ),
            )
            for spec in plan.todo
        ]
        replace = set(plan.replace)

        def store_outcome(outcome: RunOutcome) -> None:
            store.write_run(outcome.rows, replace=outcome.run_id in replace)
            replace.add(outcome.run_id)  # written once: a later write of it replaces

        report = drive(
            tasks,
            executor,
            store_outcome,
            max_in_flight=max_in_flight,
            on_outcome=on_outcome,
            respawn=respawn,
            run_fn=run_fn,
        )
        report.total = len(plan.runs)
        report.skipped = plan.skipped
        return report
    finally:
        store.close()


def drive(
    tasks: Sequence[RunTask],
    executor: Executor,
    store_outcome: Callable[[RunOutcome], None],
    *,
    max_in_flight: int,
    on_outcome: Callable[[RunOutcome], None] | None = None,
    respawn: Callable[[], Executor] | None = None,
    run_fn: RunFn = run_one,
) -> SweepReport:
    """The submission loop: keep up to ``max_in_flight`` runs going, store each outcome
    as soon as it arrives."""
    started = time.perf_counter()
    report = SweepReport(total=len(tasks), skipped=0)
    pending: deque[RunTask] = deque(tasks)
    strikes: dict[str, int] = {}
    in_flight: dict[Future[RunOutcome], RunTask] = {}
    limit = max(1, max_in_flight)

    def finish(outcome: RunOutcome) -> None:
        store_outcome(outcome)
        if outcome.status == "ok":
            report.ok += 1
        else:
            report.failed += 1
            report.failures.append((outcome.run_id, outcome.status, outcome.message))
        if on_outcome is not None:
            on_outcome(outcome)

    while pending or in_flight:
        broken = False
        while pending and len(in_flight) < limit:
            task = pending.popleft()
            try:
                in_flight[executor.submit(run_fn, task)] = task
            except BrokenExecutor:
                pending.appendleft(task)
                broken = True
                break
        done, _ = wait(in_flight, return_when=FIRST_COMPLETED) if in_flight else (set(), set())
        for future in done:
            task = in_flight.pop(future)
            try:
                outcome = future.result()
            except BrokenExecutor:
                broken = True
                pending.appendleft(task)
                strikes[task.spec.run_id] = strikes.get(task.spec.run_id, 0) + 1
                continue
            except Exception as err:  # e.g. a Dask worker lost, a result not unpickled
                outcome = failed_outcome(task, "error", f"{type(err).__name__}: {err}", None)
            finish(outcome)  # storage failing (a full disk) stops the sweep here
        if not broken:
            continue
        # A broken pool fails every run in flight; collect them all before going on.
        for future in wait(in_flight).done:
            task = in_flight.pop(future)
            try:
                outcome = future.result()
            except Exception:
                pending.appendleft(task)
                strikes[task.spec.run_id] = strikes.get(task.spec.run_id, 0) + 1
                continue
            finish(outcome)
        # The run that killed its worker is among those in flight; each was in flight
        # at most MAX_STRIKES times before it is recorded as failed.
        for task in [t for t in pending if strikes.get(t.spec.run_id, 0) >= MAX_STRIKES]:
            pending.remove(task)
            finish(failed_outcome(task, "error", "worker process died during this run", None))
        executor.shutdown(wait=False, cancel_futures=True)
        if respawn is None:
            report.not_run = len(pending)
            break
        executor = respawn()
    report.wall_time_s = time.perf_counter() - started
    return report
