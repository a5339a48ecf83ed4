"""``mrcomm fsm``: write a behaviour's state-machine diagram."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from mrcomm.agents.behaviours import behaviour_class
from mrcomm.agents.diagram import graphviz_available, mermaid, render
from mrcomm.cli.files import check_writable, write_atomically
from mrcomm.errors import InputError

_FORMATS = {".svg": "svg", ".png": "png", ".mmd": "mermaid", ".md": "mermaid"}


def fsm(
    behaviour: Annotated[str, typer.Option(help="Behaviour: nb | lf.")] = "lf",
    out: Annotated[Path, typer.Option(help="Output file: .svg/.png (graphviz) or .mmd.")] = Path(
        "fsm.svg"
    ),
) -> None:
    """Write the behaviour's (hierarchical) state machine as a diagram. Without graphviz
    installed, an .svg/.png request falls back to Mermaid text next to it (.mmd)."""
    behaviour_class(behaviour)  # unknown name -> one-line error
    fmt = _FORMATS.get(out.suffix.lower())
    if fmt is None:
        raise InputError(
            f"unsupported diagram format {out.suffix!r}; use .svg, .png or .mmd", field="--out"
        )
    check_writable(out, "--out")
    if fmt != "mermaid" and not graphviz_available():
        fallback = out.with_suffix(".mmd")
        typer.echo(f"graphviz (dot) is not installed: writing Mermaid text to {fallback}", err=True)
        out, fmt = fallback, "mermaid"
    if fmt == "mermaid":
        text = mermaid(behaviour)
        write_atomically(out, lambda tmp: _write_text(tmp, text + "\n"))
    else:
        data = render(behaviour, fmt)
        write_atomically(out, lambda tmp: _write_bytes(tmp, data))
    typer.echo(f"wrote {out}")


def _write_text(path: Path, text: str) -> None:
    path.write_text(text)


def _write_bytes(path: Path, data: bytes) -> None:
    path.write_bytes(data)
