"""Entry point of the ``mrcomm`` command: mounts every sub-command and turns bad input
(:class:`~mrcomm.errors.InputError`) into a one-line error with exit status 2."""

from __future__ import annotations

import sys
from typing import Any

import typer

from mrcomm.errors import InputError

cli = typer.Typer(
    name="mrcomm",
    help="MRComm: multi-robot teams under degraded communication.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def app() -> Any:
    """Console-script entry: run the CLI, reporting bad input in one line (exit 2)."""
    try:
        return cli(standalone_mode=True)
    except InputError as err:
        typer.echo(f"mrcomm: error: {err.one_line()}", err=True)
        sys.exit(2)
