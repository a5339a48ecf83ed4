"""Entry point of the ``mrcomm`` command: mounts every sub-command and turns bad input
(:class:`~mrcomm.errors.InputError`, or a usage error) into a one-line error with exit
status 2 and no traceback."""

from __future__ import annotations

import sys

import typer

from mrcomm.cli.analyze_cmd import analyze
from mrcomm.cli.check_cmd import check
from mrcomm.cli.fsm_cmd import fsm
from mrcomm.cli.live_cmd import agent, collect_cmd, live, world
from mrcomm.cli.pulse_cmd import pulse
from mrcomm.cli.replay_cmd import replay
from mrcomm.cli.report_cmd import report
from mrcomm.cli.run_cmd import run
from mrcomm.cli.signal_cmd import signal_app
from mrcomm.cli.sweep_cmd import export, sweep
from mrcomm.cli.variants_cmd import variants
from mrcomm.errors import InputError

cli = typer.Typer(
    name="mrcomm",
    help="MRComm: multi-robot teams under degraded communication.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@cli.callback()
def _group() -> None:
    """MRComm: simulate multi-robot missions under degraded communication and measure
    what the network did to the team."""


cli.command("run")(run)
cli.command("fsm")(fsm)
cli.command("world")(world)
cli.command("agent")(agent)
cli.command("live")(live)
cli.command("collect")(collect_cmd)
cli.command("sweep")(sweep)
cli.command("export")(export)
cli.command("replay")(replay)
cli.add_typer(signal_app, name="signal")
cli.command("pulse")(pulse)
cli.command("analyze")(analyze)
cli.command("report")(report)
cli.command("variants")(variants)
cli.command("check")(check)


def app() -> None:
    """Console-script entry: run the CLI, reporting bad input in one line (exit 2)."""
    try:
        code = cli(standalone_mode=False)
    except InputError as err:
        typer.echo(f"mrcomm: error: {err.one_line()}", err=True)
        sys.exit(2)
    except typer.Exit as err:
        sys.exit(err.exit_code)
    except typer.Abort:
        typer.echo("mrcomm: aborted", err=True)
        sys.exit(130)
    except typer.TyperException as err:
        ctx = getattr(err, "ctx", None)
        if type(err).__name__ == "NoArgsIsHelpError" and ctx is not None:
            typer.echo(ctx.get_help())  # bare `mrcomm` or `mrcomm signal`: show help
            sys.exit(0)
        # Usage errors (unknown option, bad value type) exit 2, like every bad input.
        message = " ".join(err.format_message().split())
        typer.echo(f"mrcomm: error: {message}", err=True)
        sys.exit(err.exit_code)
    sys.exit(code if isinstance(code, int) else 0)
