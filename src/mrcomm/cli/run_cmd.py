"""``mrcomm run``: simulate one mission and report what the network did to the team."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from mrcomm.cli.db_option import (
    DbOpt,
    ExperimentOpt,
    KeepDuplicateOpt,
    check_db,
    store_run,
    stored_json,
)
from mrcomm.cli.display import fmt
from mrcomm.cli.run_options import with_run_options
from mrcomm.fileio import atomic_write
from mrcomm.output_paths import FIGURE_SUFFIXES, RECORDING_SUFFIXES, check_output_file
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import run_mission

if TYPE_CHECKING:
    from mrcomm.experiment.adhoc import StoredRun
    from mrcomm.run.config import RunConfig


@with_run_options
def run(
    run: RunConfig,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    plot: Annotated[Path | None, typer.Option(help="Write a map/trajectory figure (PNG/SVG).")] = (
        None
    ),
    record: Annotated[
        Path | None, typer.Option(help="Record the run to an MCAP file (opens in Foxglove).")
    ] = None,
    db: DbOpt = None,
    experiment: ExperimentOpt = None,
    keep_duplicate: KeepDuplicateOpt = False,
) -> None:
    """Run one mission in simulation (faster than real time); with --db, store it in a
    results database (mode sim)."""
    config = run
    # Every output is checked before the mission: none can fail at its end.
    if plot is not None:
        check_output_file(plot, "--plot", FIGURE_SUFFIXES)
    if record is not None:
        check_output_file(record, "--record", RECORDING_SUFFIXES)
    check_db(db, experiment)
    if record is not None:
        from mrcomm.experiment.recording import run_and_record

        result = run_and_record(config, None, record)
    else:
        result = run_mission(config)
    if plot is not None:
        from mrcomm.analysis.mission_plot import save_mission_plot

        atomic_write(plot, lambda tmp: save_mission_plot(result, tmp, fmt=plot.suffix[1:]))
    stored = store_run(
        db,
        experiment,
        result,
        keep_duplicate=keep_duplicate,
        if_lost="the run is deterministic: run the command again",
    )
    show_result(result, result.summary(), stored, as_json)


def show_result(
    result: MissionResult,
    summary: dict[str, Any],
    stored: StoredRun | None,
    as_json: bool,
    footer: str = "",
) -> None:
    """What ``run``, ``live`` and ``collect`` print: ``summary`` as one JSON object
    (with where the run was stored), or the tables, where it was stored and ``footer``."""
    if as_json:
        if stored is not None:
            summary = {**summary, "stored": stored_json(stored)}
        typer.echo(json.dumps(summary, indent=2))
        return
    console = Console()
    print_result(result, console)
    if stored is not None:
        console.print(stored.describe(), markup=False)
    if footer:
        console.print(footer)


def print_result(result: MissionResult, console: Console) -> None:
    """Human output: mission, per-robot and message tables."""
    m = result.mission
    verdict = "[green]successful[/]" if m["successful"] else "[red]failed[/]"
    console.print(
        f"[bold]{result.config['label']}[/] on {result.config['scenario_name']} "
        f"(seed {result.config['seed']}): mission {verdict}; "
        f"{result.sim_time_s:.1f} s simulated in {result.wall_time_s:.2f} s "
        f"({result.sim_time_s / max(result.wall_time_s, 1e-9):.0f}x real time)"
    )
    mission = Table(title="Mission", show_header=True)
    mission.add_column("metric")
    mission.add_column("value", justify="right")
    for key in (
        "tasks_completed",
        "failed_tasks",
        "execution_phase_time",
        "total_movement_time",
        "total_distance",
        "near_collisions",
        "delay_time",
        "idle_time",
        "min_separation",
        "max_separation",
        "timed_out",
    ):
        mission.add_row(key, fmt(m.get(key)))
    console.print(mission)

    robots = Table(title="Robots")
    robots.add_column("metric")
    for rid in result.robots:
        robots.add_column(rid, justify="right")
    for key in (
        "tasks_assigned",
        "tasks_completed",
        "tasks_failed",
        "failed_tasks",
        "initialisation_time",
        "movement_time",
        "task_execution_time",
        "distance",
        "near_collisions",
        "delay_time",
        "idle_time",
        "min_separation",
        "max_separation",
    ):
        robots.add_row(key, *(fmt(row.get(key)) for row in result.robots.values()))
    console.print(robots)

    messages = Table(title="Messages")
    messages.add_column("topic")
    for c in ("sent", "received", "dropped_loss", "dropped_range"):
        messages.add_column(c.replace("_", " "), justify="right")
    for topic, counts in result.messages.items():
        messages.add_row(topic, *(str(counts[c]) for c in counts))
    console.print(messages)
