"""Output-file helpers for commands: check early that an output can be written, and
write atomically so that nothing is ever half-written."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from mrcomm.errors import InputError
from mrcomm.fileio import atomic_write


def check_writable(path: Path, option: str) -> None:
    """Fail before any work when ``path``'s directory does not exist."""
    parent = path.expanduser().resolve().parent
    if not parent.is_dir():
        raise InputError(f"directory {parent} does not exist", file=path, field=option)


def write_atomically(path: Path, write: Callable[[Path], object]) -> None:
    """Write an output file all at once or not at all (see :mod:`mrcomm.fileio`)."""
    atomic_write(path.expanduser(), write)
