"""Output paths: checked before any work (so a simulation or sweep never
fails at its end for want of a writable file), and written atomically (so nothing is
ever half-written).

Every check raises a one-line :class:`~mrcomm.errors.InputError` naming the option and
the path: a directory where a file is expected (or the reverse), an extension the
command cannot write, a parent that is missing or is a regular file, a directory the
user may not write into. Nothing is created by a check: the writability probe is a
temporary file removed at once.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

from mrcomm.errors import InputError

#: Extensions of each kind of output file, first one preferred.
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")
RECORDING_SUFFIXES = (".mcap",)
DATABASE_SUFFIXES = (".duckdb", ".db", ".ddb")


def check_output_file(path: Path, option: str, suffixes: Iterable[str] | None = None) -> None:
    """Fail before any work unless ``path`` can be written as a file with one of
    ``suffixes`` (None: any extension)."""
    path = path.expanduser()
    if path.is_dir():
        raise InputError("is a directory; give a file name", file=path, field=option)
    if suffixes is not None:
        allowed = tuple(suffixes)
        if path.suffix.lower() not in allowed:
            shown = repr(path.suffix) if path.suffix else "none"
            raise InputError(
                f"unsupported extension {shown}; use {', '.join(allowed)}", file=path, field=option
            )
    _check_directory_writable(path.parent, path, option)
    if path.exists() and not os.access(path, os.W_OK):
        raise InputError(
            "exists and cannot be overwritten (permission denied)", file=path, field=option
        )


def check_output_dir(path: Path, option: str) -> None:
    """Fail before any work unless ``path`` is a writable directory or can be created
    as one in an existing directory (it is not created here)."""
    path = path.expanduser()
    if path.exists() and not path.is_dir():
        raise InputError("exists and is not a directory", file=path, field=option)
    _check_directory_writable(path if path.is_dir() else path.parent, path, option)


def _check_directory_writable(directory: Path, path: Path, option: str) -> None:
    """``directory`` must be an existing directory that accepts a new file."""
    directory = directory.resolve()
    if directory.exists() and not directory.is_dir():
        raise InputError(f"{directory} is not a directory", file=path, field=option)
    if not directory.is_dir():
        if any(p.exists() and not p.is_dir() for p in directory.parents):
            blocker = next(p for p in directory.parents if p.exists() and not p.is_dir())
            raise InputError(f"{blocker} is not a directory", file=path, field=option)
        raise InputError(f"directory {directory} does not exist", file=path, field=option)
    try:
        handle, probe = tempfile.mkstemp(dir=directory, prefix=".mrcomm-probe-")
    except OSError as err:
        reason = err.strerror or str(err)
        raise InputError(
            f"cannot write in {directory} ({reason.lower()})", file=path, field=option
        ) from None
    os.close(handle)
    os.unlink(probe)
