"""What a sweep worker does with one run: simulate it and turn it into result rows.

:func:`run_one` is a pure function of its :class:`RunTask` (configuration, repetition,
seed) and never raises for a run that goes wrong: a crash becomes an ``error`` outcome
with the exception and its traceback, a run over its wall-clock limit a ``timeout``
outcome. Each worker process (or thread) loads a scenario's :class:`ScenarioResources` once and
reuses it for every run on that scenario.
"""

from __future__ import annotations

import contextlib
import functools
import os
import signal
import threading
import time
import traceback
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import FrameType

from mrcomm.experiment.rows import Rows, failure_rows, result_rows
from mrcomm.experiment.schema import RunSpec
from mrcomm.live.leftovers import alive
from mrcomm.run.config import RunConfig
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import Mission

#: Steps between two looks at the wall clock (a step is ~0.1-1 ms).
_CLOCK_EVERY = 50
#: Longest error text stored (the first line is the message, then the traceback).
_ERROR_CHARS = 4000


class RunTimeout(Exception):
    """A run exceeded its wall-clock limit."""


@dataclass(frozen=True)
class RunTask:
    """A run as sent to a worker."""

    spec: RunSpec
    #: Wall-clock limit of the run, s (None: no limit).
    timeout_s: float | None = None
    #: Where to write the run's MCAP recording (None: no recording).
    record_path: str | None = None


@dataclass(frozen=True)
class RunOutcome:
    """What came back from a worker: status and the rows to store."""

    run_id: str
    status: str  # 'ok' | 'error' | 'timeout'
    error: str | None
    wall_time_s: float
    rows: Rows

    @property
    def message(self) -> str:
        """First line of the error (empty when ok)."""
        return (self.error or "").splitlines()[0] if self.error else ""


@functools.lru_cache(maxsize=8)
def _resources(scenario: str) -> ScenarioResources:
    # One ScenarioResources per scenario per worker: the planner's cost grid is built once.
    return ScenarioResources.load(Path(scenario))


def failed_outcome(task: RunTask, status: str, error: str, wall: float | None) -> RunOutcome:
    error = error[:_ERROR_CHARS]
    return RunOutcome(
        task.spec.run_id, status, error, wall or 0.0, failure_rows(task.spec, status, error, wall)
    )


def run_one(task: RunTask) -> RunOutcome:
    """Simulate one run (and record it if asked); never raises for a failed run."""
    start = time.perf_counter()
    deadline = start + task.timeout_s if task.timeout_s is not None else None
    try:
        resources = _resources(str(task.spec.config.scenario))
        if task.record_path is not None:
            result = _record(task.spec.config, resources, Path(task.record_path), deadline)
        else:
            result = _simulate(task.spec.config, resources, deadline)
        wall = time.perf_counter() - start
        return RunOutcome(task.spec.run_id, "ok", None, wall, result_rows(task.spec, result, wall))
    except RunTimeout:
        wall = time.perf_counter() - start
        return failed_outcome(
            task, "timeout", f"RunTimeout: wall-clock limit of {task.timeout_s:g} s exceeded", wall
        )
    except Exception as err:  # a crashing run is a result of the sweep, not its end
        wall = time.perf_counter() - start
        text = f"{type(err).__name__}: {err}".replace("\n", " ")
        return failed_outcome(task, "error", f"{text}\n{traceback.format_exc()}", wall)


def _simulate(
    config: RunConfig, resources: ScenarioResources, deadline: float | None
) -> MissionResult:
    mission = Mission(config, resources)
    start = time.perf_counter()
    while not mission.done:
        mission.step()
        if (
            deadline is not None
            and mission.steps % _CLOCK_EVERY == 0
            and time.perf_counter() > deadline
        ):
            raise RunTimeout
    result = mission.result()
    result.wall_time_s = time.perf_counter() - start
    return result


def _record(
    config: RunConfig, resources: ScenarioResources, path: Path, deadline: float | None
) -> MissionResult:
    # run_and_record writes to a temporary name and renames when complete, so a killed
    # or failed run never leaves a truncated recording under the run's name.
    from mrcomm.experiment.recording import run_and_record

    with _alarm(deadline):
        return run_and_record(config, resources, path)


@contextlib.contextmanager
def _alarm(deadline: float | None) -> Iterator[None]:
    """Raise RunTimeout at ``deadline`` (recordings step the mission themselves).

    Only possible in a process's main thread (a process-pool worker); elsewhere (threaded
    executors) recorded runs have no wall-clock limit.
    """
    usable = (
        deadline is not None
        and hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
    )
    if not usable:
        yield
        return
    assert deadline is not None

    def expire(signum: int, frame: FrameType | None) -> None:
        raise RunTimeout

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, max(deadline - time.perf_counter(), 1e-3))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def ignore_interrupts() -> None:
    """Process-pool initializer: Ctrl-C is the parent's to handle (it stops submitting
    and lets the runs in flight end); a worker must not die of it mid-run."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


#: How often a worker checks that the sweep that started it is still there (s).
PARENT_CHECK_S = 1.0


def start_worker(sweep_pid: int) -> None:
    """Process-pool initializer: ignore Ctrl-C (:func:`ignore_interrupts`) and end with
    the sweep process ``sweep_pid``. A worker's parent is the pool's fork server, not
    the sweep, so a sweep killed outright (SIGKILL) would leave its workers running a
    run nobody will store: a daemon thread checks every second that the sweep is still
    there and ends the worker when it is not."""
    ignore_interrupts()

    def watch() -> None:
        while True:
            time.sleep(PARENT_CHECK_S)
            if not alive(sweep_pid):  # (a recycled pid of another user's counts)
                os._exit(1)

    threading.Thread(target=watch, name="sweep-watch", daemon=True).start()
