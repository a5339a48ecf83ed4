"""``mrcomm fsm``: write a behaviour's state-machine diagram."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from mrcomm.agents.behaviours import behaviour_class
from mrcomm.agents.diagram import graphviz_available, mermaid, render
from mrcomm.fileio import atomic_write
from mrcomm.output_paths import check_output_file

_FORMATS = {".svg": "svg", ".png": "png", ".mmd": "mermaid", ".md": "mermaid"}


def fsm(
    behaviour: Annotated[
        str, typer.Option(help="A registered behaviour (mrcomm variants behaviour).")
    ] = "lf",
    out: Annotated[Path, typer.Option(help="Output file: .svg/.png (graphviz) or .mmd.")] = Path(
        "fsm.svg"
    ),
) -> None:
    """Write the behaviour's (hierarchical) state machine as a diagram. Without graphviz
    installed, an .svg/.png request falls back to Mermaid text next to it (.mmd)."""
    behaviour_class(behaviour)  # unknown name -> one-line error
    check_output_file(out, "--out", _FORMATS)
    fmt = _FORMATS[out.suffix.lower()]
    if fmt != "mermaid" and not graphviz_available():
        fallback = out.with_suffix(".mmd")
        typer.echo(f"graphviz (dot) is not installed: writing Mermaid text to {fallback}", err=True)
        out, fmt = fallback, "mermaid"
    if fmt == "mermaid":
        text = mermaid(behaviour)
        atomic_write(out, lambda tmp: _write_text(tmp, text + "\n"))
    else:
        data = render(behaviour, fmt)
        atomic_write(out, lambda tmp: _write_bytes(tmp, data))
    typer.echo(f"wrote {out}")


def _write_text(path: Path, text: str) -> None:
    path.write_text(text)


def _write_bytes(path: Path, data: bytes) -> None:
    path.write_bytes(data)
