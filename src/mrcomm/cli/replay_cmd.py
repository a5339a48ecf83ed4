"""``mrcomm replay``: summarise an MCAP recording of a mission (channels, message counts,
time spans, the mission summary and delivery outcomes per topic), read back from the
file alone."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from mrcomm.cli.display import fmt
from mrcomm.experiment.recording_reader import (
    OUTCOMES,
    RecordingSummary,
    read_recording,
    recording_label,
)


def replay(
    file: Annotated[Path, typer.Argument(help="MCAP recording (written by --record).")],
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
) -> None:
    """Summarise a recorded mission (open the file in Foxglove to watch it)."""
    summary = read_recording(file)
    if as_json:
        typer.echo(json.dumps(summary.as_dict(), indent=2))
    else:
        print_summary(summary, Console())


def print_summary(summary: RecordingSummary, console: Console) -> None:
    """Human output: channels, mission summary and message outcomes."""
    result = summary.result
    span = max((c.end for c in summary.channels if c.end is not None), default=0.0)
    console.print(
        f"[bold]{summary.path}[/]: {recording_label(summary)}, "
        f"{summary.message_count} messages on {len(summary.channels)} channels, "
        f"{span:.1f} s simulated"
    )
    channels = Table(title="Channels")
    channels.add_column("topic")
    channels.add_column("schema")
    for col in ("messages", "start s", "end s"):
        channels.add_column(col, justify="right")
    for c in summary.channels:
        channels.add_row(c.topic, c.schema, str(c.count), fmt(c.start), fmt(c.end))
    console.print(channels)

    if result is None:
        console.print("[yellow]no /result message: the recording has no mission summary[/]")
    else:
        mission = result.get("mission", {})
        verdict = "[green]successful[/]" if mission.get("successful") else "[red]failed[/]"
        config = result.get("config", {})
        console.print(
            f"Mission {verdict} (scenario {config.get('scenario_name', '?')}, seed "
            f"{config.get('seed', '?')}): {mission.get('tasks_completed', '?')} tasks completed,"
            f" failed tasks: {fmt(mission.get('failed_tasks'))}, execution phase "
            f"{fmt(mission.get('execution_phase_time'))} s, timed out: "
            f"{fmt(mission.get('timed_out'))}"
        )

    outcomes = Table(title="Message outcomes (/messages)")
    outcomes.add_column("topic")
    # The radio's causes only when the recording has them.
    shown = [o for o in OUTCOMES if any(o in c for c in summary.outcomes.values())]
    for o in shown:
        outcomes.add_column(o.replace("_", " "), justify="right")
    for topic, counts in summary.outcomes.items():
        outcomes.add_row(topic, *(str(counts.get(o, 0)) for o in shown))
    console.print(outcomes)
