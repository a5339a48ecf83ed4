"""``mrcomm console``: the operator console on a finished mission (``--replay``: an MCAP
recording scrubbed with a time slider). A running simulated mission gets its console
with ``mrcomm run --console``."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Annotated

import typer

from mrcomm.errors import InputError


def need_console_extra(field: str, *modules: str) -> None:
    """One line (exit status 2) when the console extra is not installed: NiceGUI, and
    ``modules`` besides."""
    for module in ("nicegui", *modules):
        if importlib.util.find_spec(module) is None:
            raise InputError(
                f"needs the console extra: pip install 'mrcomm[console]' ({module} missing)",
                field=field,
            )


def console(
    replay: Annotated[
        Path, typer.Option(help="An MCAP recording (mrcomm run --record) to scrub through.")
    ],
    port: Annotated[int, typer.Option(min=1, max=65535, help="Port of the page.")] = 8080,
) -> None:
    """Open a recorded mission in the operator console (http://localhost:--port)."""
    need_console_extra("--replay", "mcap_protobuf")
    from mrcomm.console.guard import ConsoleGuard
    from mrcomm.console.page import serve_replay
    from mrcomm.console.replay import load_replay

    loaded = load_replay(replay)
    guard = ConsoleGuard(port)
    typer.echo(f"console: {guard.url} ({loaded.label}, {loaded.end:.1f} s)", err=True)
    serve_replay(loaded, guard)
