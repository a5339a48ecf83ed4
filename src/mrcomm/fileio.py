"""Atomic file output: whatever MRComm writes (maps, models, CSVs, figures, reports,
recordings, exports) goes to a temporary file next to its target and is renamed into
place only once complete, so an error or a kill never leaves a half-written file.

``stage`` + ``commit`` let a caller write several files and rename them together (a map
is a YAML and an image); ``atomic_write`` does both for one file; ``staged_directory``
does the same for a directory of files (a generated or copied scenario).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from mrcomm.errors import InputError


@contextmanager
def staged_directory(out: Path, option: str) -> Iterator[Path]:
    """A new directory to fill, renamed to ``out`` (absent or empty) when the block
    ends without error, removed otherwise. Every problem with ``out`` is a one-line
    InputError naming ``option``, raised before the block runs."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise InputError("exists and is not an empty directory", file=out, field=option)
    parent = out.resolve().parent
    if not parent.is_dir():
        raise InputError("its parent directory does not exist", file=out, field=option)
    # Made first: an unwritable directory fails now, not after the work.
    try:
        staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=parent))
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes it private; make it usual
    except OSError as err:
        raise InputError(f"cannot write there: {err.strerror}", file=out, field=option) from None
    try:
        yield staging
        try:
            if out.exists():
                out.rmdir()
            staging.rename(out)
        except OSError as err:
            raise InputError(
                f"cannot move the files into place: {err.strerror}", file=out, field=option
            ) from None
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def stage(target: str | Path, write: Callable[[Path], object]) -> Path:
    """Call ``write(tmp)`` on a temporary file next to ``target`` and return it, written,
    flushed to disk and with the permissions the target will have (an existing target's
    mode, else the usual 0666 less the umask — mkstemp alone makes files private). On
    any error the temporary file is removed."""
    target = Path(target)
    fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        with open(tmp, "rb+") as handle:
            os.fsync(handle.fileno())
        os.chmod(tmp, _mode_for(target))
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return tmp


def commit(tmp: Path, target: str | Path) -> None:
    """Rename a staged file over its target (atomic on one file system)."""
    os.replace(tmp, target)


def atomic_write(target: str | Path, write: Callable[[Path], object]) -> None:
    """Write ``target`` through ``write(tmp)``: all of it or, on error, nothing."""
    target = Path(target)
    tmp = stage(target, write)
    try:
        commit(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write_bytes(target: str | Path, data: bytes) -> None:
    atomic_write(target, lambda tmp: tmp.write_bytes(data))


def atomic_write_text(target: str | Path, text: str) -> None:
    atomic_write(target, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def _mode_for(target: Path) -> int:
    if target.exists():
        return target.stat().st_mode & 0o777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask
