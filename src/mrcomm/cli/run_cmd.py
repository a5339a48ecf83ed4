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
from mrcomm.cli.progress import MissionProgress, ProgressLine
from mrcomm.cli.run_options import warn_ignored_settings, with_run_options
from mrcomm.fileio import atomic_write
from mrcomm.metrics.units import unit_of
from mrcomm.net.delivery import (
    DELAY_KEYS,
    DROP_CAUSES,
    count_keys,
    has_radio_counts,
    has_shared_counts,
)
from mrcomm.output_paths import FIGURE_SUFFIXES, RECORDING_SUFFIXES, check_output_file
from mrcomm.run.assemble import AON_TOTAL_KEYS
from mrcomm.run.result import MissionResult
from mrcomm.sim.mission import run_mission
from mrcomm.specs import get_spec

if TYPE_CHECKING:
    from mrcomm.experiment.adhoc import StoredRun
    from mrcomm.run.config import RunConfig


@with_run_options
def run(
    run: RunConfig,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    quiet: Annotated[
        bool, typer.Option("--quiet", help="No progress line (there is none when piped).")
    ] = False,
    plot: Annotated[Path | None, typer.Option(help="Write a map/trajectory figure (PNG/SVG).")] = (
        None
    ),
    record: Annotated[
        Path | None, typer.Option(help="Record the run to an MCAP file (opens in Foxglove).")
    ] = None,
    foxglove: Annotated[
        bool,
        typer.Option(
            "--foxglove",
            help="Stream the run live to the Foxglove app (a Foxglove WebSocket server on "
            "--foxglove-port; the same channels as --record).",
        ),
    ] = False,
    foxglove_port: Annotated[
        int, typer.Option(min=0, max=65535, help="Port of the --foxglove server (0: any free).")
    ] = 8765,
    speed: Annotated[
        float | None,
        typer.Option(
            min=0.001,
            help="Pace the mission at this many times real time (default: as fast as "
            "possible); with --foxglove, to watch it.",
        ),
    ] = None,
    operator: Annotated[
        Path | None,
        typer.Option(
            help="An operator in the loop: a YAML file with where it sits and the commands "
            "it sends when (reassign, redo, add, pause, resume; README)."
        ),
    ] = None,
    console: Annotated[
        bool,
        typer.Option(
            "--console",
            help="Watch and steer the run in a browser: the operator console on "
            "http://localhost:--port (paced at --speed, default x1; needs mrcomm[console]).",
        ),
    ] = False,
    port: Annotated[int, typer.Option(min=1, max=65535, help="Port of the --console page.")] = (
        8080
    ),
    exit_on_end: Annotated[
        bool,
        typer.Option(
            "--exit-on-end",
            help="With --console: stop serving the page when the mission ends (for scripts; "
            "by default it stays up with the final state until Ctrl-C or its quit button).",
        ),
    ] = False,
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
    warn_ignored_settings(config)
    resources, plan = None, None
    if operator is not None:
        from mrcomm.run.operator_plan import load_operator_plan
        from mrcomm.run.resources import ScenarioResources

        resources = ScenarioResources.load(config.scenario)
        reassignable = config.spec("behaviour").accepts_reassignment
        plan = load_operator_plan(operator, resources.scenario, reassignable=reassignable)
    if console:
        result = _run_with_console(
            config, resources, plan, speed, port, record is not None, exit_on_end
        )
    else:
        enabled = not (as_json or quiet)
        status = "loading the scenario, planning"
        with ProgressLine("mission", config.max_time, enabled=enabled, status=status) as line:
            progress = MissionProgress(line) if line.enabled else None
            if record is not None or foxglove or speed is not None:
                from mrcomm.experiment.recording import run_and_record

                def serving(port: int) -> None:
                    typer.echo(f"Foxglove: open ws://localhost:{port} in the Foxglove app",
                               err=True)  # fmt: skip

                serve = ("127.0.0.1", foxglove_port) if foxglove else None
                result = run_and_record(
                    config, resources, record, serve=serve, speed=speed, on_serving=serving,
                    operator=plan, progress=progress,
                )  # fmt: skip
            else:
                result = run_mission(config, resources, plan, progress)
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


def _run_with_console(
    config: RunConfig,
    resources: Any,
    plan: Any,
    speed: float | None,
    port: int,
    recording: bool,
    exit_on_end: bool,
) -> MissionResult:
    """The run paced under the operator console (its own page; see mrcomm.console).
    The page stays up once the mission ends, unless ``exit_on_end``."""
    from mrcomm.errors import InputError

    if recording:
        raise InputError("--console and --record cannot be combined yet", field="--console")
    from mrcomm.cli.console_cmd import need_console_extra

    need_console_extra("--console")
    from mrcomm.console.guard import ConsoleGuard
    from mrcomm.console.page import serve
    from mrcomm.console.session import ConsoleSession

    session = ConsoleSession(config, resources, plan, speed if speed is not None else 1.0)
    guard = ConsoleGuard(port)
    typer.echo(f"console: {guard.url}", err=True)

    def ended(result: MissionResult) -> None:
        verdict = "successful" if result.mission["successful"] else "failed"
        typer.echo(f"console: mission ended ({verdict}); the page shows its final state "
                   "until Ctrl-C or its quit button", err=True)  # fmt: skip

    serve(session, guard, session.run, stay_up=None if exit_on_end else ended)
    if session.result is None:
        raise InputError("the console stopped before the mission ended", field="--console")
    return session.result


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


#: Robots beyond which the per-robot table is left to --json (it would not fit).
MAX_ROBOT_COLUMNS = 8
#: Robot pairs beyond which the link table shows a summary only.
MAX_LINK_ROWS = 15

_MISSION_KEYS = (
    "tasks_completed",
    "failed_tasks",
    "execution_phase_time",
    "total_movement_time",
    "total_distance",
    "near_collisions",
    "near_collisions_filtered",
    "near_collisions_confirmed",
    "near_collisions_false",
    "near_collisions_missed",
    "delay_time",
    "idle_time",
    "task_execution_time",
    "min_separation",
    "max_separation",
    "tasks_per_minute",
    "assigner_connected",
    "largest_group_mean",
    "largest_group_min",
    "timed_out",
)
_ROBOT_KEYS = (
    "tasks_assigned",
    "tasks_completed",
    "tasks_failed",
    "failed_tasks",
    "initialisation_time",
    "movement_time",
    "task_execution_time",
    "distance",
    "near_collisions",
    "near_collisions_false",
    "near_collisions_missed",
    "delay_time",
    "idle_time",
    "min_separation",
    "max_separation",
)
_AON_KEYS = ("statuses_sent", *AON_TOTAL_KEYS, "max_finish_time")


def _named(key: str) -> str:
    """``key (unit)`` for a table's first column."""
    unit = unit_of(key)
    return f"{key} ({unit})" if unit and unit != "yes/no" else key


def _table(title: str, *columns: str) -> Table:
    table = Table(title=title, title_justify="left")
    for i, column in enumerate(columns):
        first = i == 0
        table.add_column(column, justify="left" if first else "right", no_wrap=first)
    return table


def print_result(result: MissionResult, console: Console) -> None:
    """Human output, every metric group with its unit: mission, robots, Leader–Follower,
    AON, links, messages (see docs/GLOSSARY.md for definitions)."""
    m = result.mission
    verdict = "[green]successful[/]" if m["successful"] else "[red]failed[/]"
    console.print(
        f"[bold]{result.config['label']}[/] on {result.config['scenario_name']} "
        f"(seed {result.config['seed']}): mission {verdict}; "
        f"{result.sim_time_s:.1f} s simulated in {result.wall_time_s:.2f} s "
        f"({result.sim_time_s / max(result.wall_time_s, 1e-9):.0f}x real time)"
    )
    mission = _table("Mission", "metric", "value")
    for key in _MISSION_KEYS:
        value = m.get(key)
        shown = (
            f"{fmt(value)} of {m.get('tasks_total')}" if key == "tasks_completed" else fmt(value)
        )
        mission.add_row(_named(key), shown)
    console.print(mission)

    robots = list(result.robots)
    if len(robots) <= MAX_ROBOT_COLUMNS:
        table = _table("Robots", "metric", *robots)
        for key in _ROBOT_KEYS:
            table.add_row(_named(key), *(fmt(result.robots[r].get(key)) for r in robots))
        console.print(table)
    else:
        console.print(f"Robots: {len(robots)} (per-robot metrics: --json)")

    spec = get_spec("behaviour", str(result.config["behaviour"]))
    if spec.team_metrics:
        team = _table(f"{spec.name} (team totals)", "metric", "value")
        for metric in spec.team_metrics:
            team.add_row(f"{metric.name} ({metric.unit})", fmt(m.get(metric.name)))
        console.print(team)

    commands = result.operator.get("commands", [])
    if commands:
        table = _table("Operator commands", "time (s)", "command", "robot", "task",
                       "acknowledged by", "finished (s)")  # fmt: skip
        for c in commands:
            acked = ", ".join(m for m in c["acknowledged"] if m != "operator")
            table.add_row(fmt(c["time"]), c["command"], c["robot"], c["task_id"] or "-",
                          acked or "-", fmt(c["finished_at"]))  # fmt: skip
        console.print(table)

    total = result.aon.get("total") or {}
    if total:
        aon = _table("AON (All-Or-Nothing messaging)", "metric", "value")
        for key in _AON_KEYS:
            aon.add_row(_named(key), fmt(total.get(key)))
        console.print(aon)

    _print_links(result, console)

    radio = has_radio_counts(result.messages.values())
    keys = count_keys(radio, has_shared_counts(result.messages.values()))
    drops = [k for k in keys if k in DROP_CAUSES]
    headers = ["topic", "sent", "received", *(DROP_CAUSES[k] for k in drops), "not received %"]
    if radio:
        headers += ["mean delay s", "max delay s"]
    messages = _table("Messages", *headers)
    for topic, counts in result.messages.items():
        lost = sum(counts[k] for k in drops)
        attempts = counts["received"] + lost
        share = f"{100.0 * lost / attempts:.1f}" if attempts else "-"
        delays = [f"{counts.get(k, 0.0):.4f}" for k in DELAY_KEYS] if radio else []
        messages.add_row(topic, *(str(counts[k]) for k in keys), share, *delays)
    console.print(messages)


def _print_links(result: MissionResult, console: Console) -> None:
    """Robot pairs (one direction each): distances, warnings, time out of range."""
    robots = set(result.robots)
    pairs = []
    for name, row in result.links.items():
        a, _, b = name.partition("->")
        if a in robots and b in robots and a < b:
            pairs.append((f"{a}–{b}", row))
    if not pairs:
        return
    columns = {
        "min_distance": "closest (m)",
        "max_distance": "furthest (m)",
        "min_rssi": "min RSSI (dBm)",
        "time_in_warning": "in warning (s)",
        "warnings": "warnings",
        "time_disconnected": "out of range (s)",
    }
    if len(pairs) > MAX_LINK_ROWS:
        out = [row["time_disconnected"] for _, row in pairs]
        console.print(
            f"Links: {len(pairs)} robot pairs; out of range {sum(o > 0 for o in out)} of them, "
            f"longest {max(out):.1f} s (per pair: --json)"
        )
        return
    table = _table("Links (robot pairs)", "pair", *columns.values())
    for name, row in pairs:
        table.add_row(name, *(fmt(row.get(k)) for k in columns))
    console.print(table)
