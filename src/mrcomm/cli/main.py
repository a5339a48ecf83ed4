"""Entry point of the ``mrcomm`` command: lists every sub-command, imports a
sub-command's module only when that command runs (so ``mrcomm --help`` and
``mrcomm --version`` answer at once, without loading numpy, scipy or Zenoh), and turns
bad input (:class:`~mrcomm.errors.InputError`, or a usage error) into a one-line error
with exit status 2 and no traceback. Ctrl-C ends any command with one line and exit
status 130."""

from __future__ import annotations

import importlib
import sys
from typing import Any, NamedTuple

import typer
from typer.core import TyperGroup

import mrcomm
from mrcomm.errors import InputError, Interrupted, MissionFailed

#: Exit status after Ctrl-C (128 + SIGINT, as shells report it).
EXIT_INTERRUPTED = 130


class Command(NamedTuple):
    module: str
    attribute: str
    #: The line ``mrcomm --help`` shows: kept here so that listing the commands imports
    #: none of them (tests/cli/test_main_cli.py loads every entry).
    summary: str


_CLI = "mrcomm.cli."
#: Every sub-command, in the order ``mrcomm --help`` lists them.
COMMANDS: dict[str, Command] = {
    "run": Command(
        _CLI + "run_cmd", "run", "Run one mission in simulation (faster than real time)"
    ),
    "sweep": Command(
        _CLI + "sweep_cmd", "sweep", "Run every configuration x repetition of an experiment"
    ),
    "analyze": Command(_CLI + "analyze_cmd", "analyze", "Print the statistics of a study"),
    "report": Command(
        _CLI + "report_cmd", "report", "Write a study's HTML report, figures and tables"
    ),
    "export": Command(
        _CLI + "sweep_cmd", "export", "Export every results table to CSV or Parquet files"
    ),
    "scenario": Command(
        _CLI + "scenario_cmd", "scenario_app", "Scenarios: make, tasks, show; bundled: list, copy"
    ),
    "live": Command(_CLI + "live_cmd", "live", "Run one mission live over Zenoh"),
    "world": Command(
        _CLI + "process_cmd", "world", "Simulate every robot's base and publish the clock (live)"
    ),
    "agent": Command(_CLI + "process_cmd", "agent", "Run one robot's agent over Zenoh"),
    "team": Command(
        _CLI + "team_cmd", "team_app", "Team certificates for live mode: init, add, show"
    ),
    "collect": Command(
        _CLI + "live_cmd", "collect_cmd", "Merge the records of a live run into one result"
    ),
    "replay": Command(_CLI + "replay_cmd", "replay", "Summarise a recorded mission (MCAP)"),
    "console": Command(
        _CLI + "console_cmd", "console", "Open a recorded mission in the operator console"
    ),
    "pulse": Command(_CLI + "pulse_cmd", "pulse", "ESD pulse: publish the measured RSSI"),
    "signal": Command(_CLI + "signal_cmd", "signal_app", "SSD signal models: fit, show, plot"),
    "radio": Command(
        _CLI + "radio_cmd",
        "radio_app",
        "Radio model profiles: list, show, plot, fit, validate",
    ),
    "fsm": Command(_CLI + "fsm_cmd", "fsm", "Write a behaviour's state machine as a diagram"),
    "variants": Command(
        _CLI + "variants_cmd", "variants", "List every registered variant with its parameters"
    ),
    "check": Command(
        _CLI + "check_cmd", "check", "Check that a variant keeps the contract of every variant"
    ),
}


class LazyGroup(TyperGroup):
    """The ``mrcomm`` group: commands built from :data:`COMMANDS` on first use."""

    def list_commands(self, ctx: Any) -> list[str]:
        return list(COMMANDS)

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        entry = COMMANDS.get(cmd_name)
        if entry is None:
            return None
        target = getattr(importlib.import_module(entry.module), entry.attribute)
        if isinstance(target, typer.Typer):
            return typer.main.get_group(target)
        app = typer.Typer(rich_markup_mode=None, pretty_exceptions_enable=False)
        app.command(cmd_name)(target)
        return typer.main.get_command(app)

    def format_commands(self, ctx: Any, formatter: Any) -> None:
        # The summaries from the table: asking each command would import them all.
        rows = [(name, entry.summary + ".") for name, entry in COMMANDS.items()]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


def _version(ctx: Any, _: Any, value: bool) -> None:
    if value:
        typer.echo(f"mrcomm {mrcomm.__version__}")
        ctx.exit()


cli = typer.Typer(
    name="mrcomm",
    cls=LazyGroup,
    help="MRComm: simulate multi-robot missions under degraded communication and measure "
    "what the network did to the team. Acronyms and metrics: docs/GLOSSARY.md.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


@cli.callback()
def _group(
    version: bool = typer.Option(
        False,
        "--version",
        help="Print the version and exit.",
        callback=_version,
        is_eager=True,
    ),
) -> None:
    """MRComm: simulate multi-robot missions under degraded communication and measure
    what the network did to the team. Acronyms and metrics: docs/GLOSSARY.md."""


def _interrupted(message: str = "interrupted") -> None:
    typer.echo(f"mrcomm: {message}", err=True)
    sys.exit(EXIT_INTERRUPTED)


def app() -> None:
    """Console-script entry: run the CLI, reporting bad input in one line (exit 2)."""
    try:
        code = cli(standalone_mode=False)
    except InputError as err:
        typer.echo(f"mrcomm: error: {err.one_line()}", err=True)
        sys.exit(2)
    except MissionFailed as failed:
        typer.echo(f"mrcomm: error: {' '.join(str(failed).split())}", err=True)
        sys.exit(1)
    except Interrupted as stop:
        _interrupted(str(stop))
    except typer.Exit as err:
        sys.exit(err.exit_code)
    except (typer.Abort, KeyboardInterrupt):
        _interrupted()
    except typer.TyperException as err:
        ctx = getattr(err, "ctx", None)
        if type(err).__name__ == "NoArgsIsHelpError" and ctx is not None:
            typer.echo(ctx.get_help())  # bare `mrcomm` or `mrcomm signal`: show help
            sys.exit(0)
        # Usage errors (unknown option, bad value type) exit 2, like every bad input.
        message = " ".join(err.format_message().split())
        typer.echo(f"mrcomm: error: {message}", err=True)
        sys.exit(err.exit_code)
    if code == EXIT_INTERRUPTED:  # Typer turns Ctrl-C into this exit code, silently
        _interrupted()
    sys.exit(code if isinstance(code, int) else 0)
