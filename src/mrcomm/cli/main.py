"""Entry point of the ``mrcomm`` command: mounts every sub-command and turns bad input
(:class:`~mrcomm.errors.InputError`, or a usage error) into a one-line error with exit
status 2 and no traceback."""

from __future__ import annotations

import sys

import click
import typer

from mrcomm.cli.run_cmd import run
from mrcomm.errors import InputError

cli = typer.Typer(
    name="mrcomm",
    help="MRComm: multi-robot teams under degraded communication.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
cli.command("run")(run)


def app() -> None:
    """Console-script entry: run the CLI, reporting bad input in one line (exit 2)."""
    try:
        code = cli(standalone_mode=False)
    except InputError as err:
        typer.echo(f"mrcomm: error: {err.one_line()}", err=True)
        sys.exit(2)
    except click.exceptions.Exit as err:
        sys.exit(err.exit_code)
    except click.exceptions.Abort:
        typer.echo("mrcomm: aborted", err=True)
        sys.exit(130)
    except click.ClickException as err:
        message = " ".join(err.format_message().split())
        typer.echo(f"mrcomm: error: {message}", err=True)
        sys.exit(2 if isinstance(err, click.UsageError) else err.exit_code)
    sys.exit(code if isinstance(code, int) else 0)
