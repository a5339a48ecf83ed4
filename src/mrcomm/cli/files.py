"""Output-file helpers for commands: check early that an output can be written, and
write atomically so that nothing is ever half-written."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from mrcomm.errors import InputError


def check_writable(path: Path, option: str) -> None:
    """Fail before any work when ``path``'s directory does not exist."""
    parent = path.expanduser().resolve().parent
    if not parent.is_dir():
        raise InputError(f"directory {parent} does not exist", file=path, field=option)


def write_atomically(path: Path, write: Callable[[Path], None]) -> None:
    """Call ``write(tmp)`` on a temporary file next to ``path``, then rename it into
    place; the temporary file is removed on any error."""
    path = path.expanduser()
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
