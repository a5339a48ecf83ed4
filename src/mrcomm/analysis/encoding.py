"""Encoding figures as PNG, SVG and PDF bytes.

Drawing a report's figures at print resolution in three formats is most of a report's
time, and each figure is independent of the others, so :class:`Encoder` hands them to
worker processes when there is more than one CPU (the figure travels pickled; matplotlib
supports that) and encodes them in this process otherwise. The bytes are the same
either way: PNG, SVG and PDF carry no date, and SVG's element ids come from a fixed salt
instead of a random one.
"""

from __future__ import annotations

import io
import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from types import TracebackType

import matplotlib

matplotlib.use("Agg")  # figures are files; never open a window
from matplotlib.figure import Figure

#: Resolution of PNG figures: print quality.
PNG_DPI = 300

#: Salt of the ids SVG gives clip paths and markers (matplotlib's default is random).
SVG_HASH_SALT = "mrcomm"


def render(fig: Figure, fmt: str = "png", dpi: int = PNG_DPI) -> bytes:
    """The figure encoded as PNG, SVG or PDF bytes."""
    buf = io.BytesIO()
    # SVG/PDF: text stays text (smaller, searchable); no date, for reproducible files.
    meta = {"Date": None} if fmt == "svg" else {"CreationDate": None} if fmt == "pdf" else {}
    with matplotlib.rc_context({"svg.hashsalt": SVG_HASH_SALT}):
        fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta)
    return buf.getvalue()


@dataclass(frozen=True)
class Encoded:
    """One figure's files: PNG always, SVG and PDF when vector figures are wanted."""

    png: bytes
    svg: bytes | None
    pdf: bytes | None


def encode(fig: Figure, vector: bool) -> Encoded:
    """PNG, and SVG and PDF when ``vector``, of one figure."""
    png = render(fig, "png")
    # The layout is settled by the first render; freezing it makes the vector renders cheaper.
    fig.set_layout_engine("none")
    if not vector:
        return Encoded(png, None, None)
    return Encoded(png, render(fig, "svg"), render(fig, "pdf"))


def available_cpus() -> int:
    """CPUs this process may run on (the affinity mask, not the machine's count)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


class Encoder:
    """Encodes figures in ``jobs`` worker processes (in this process when ``jobs`` is 1).

    Use as a context manager; :meth:`submit` returns a future of the figure's
    :class:`Encoded` bytes. Workers are started with ``spawn`` (a fork would copy the
    caller's threads, e.g. DuckDB's, in an undefined state)."""

    def __init__(
        self, vector: bool, jobs: int, progress: Callable[[str], None] | None = None
    ) -> None:
        self.vector = vector
        #: Told "N figures drawn, M encoded" as they are (a progress line).
        self.progress = progress
        self.drawn = 0
        self.encoded = 0
        self._pool = (
            ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn"))
            if jobs > 1
            else None
        )

    def submit(self, fig: Figure) -> Future[Encoded]:
        self.drawn += 1
        if self._pool is not None:
            future = self._pool.submit(encode, fig, self.vector)
        else:
            future = Future()
            future.set_result(encode(fig, self.vector))
        self._tell()
        future.add_done_callback(self._encoded)
        return future

    def _encoded(self, _: Future[Encoded]) -> None:
        self.encoded += 1
        self._tell()

    def _tell(self) -> None:
        if self.progress is not None:
            self.progress(f"{self.drawn} figures drawn, {self.encoded} encoded")

    def __enter__(self) -> Encoder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._pool is not None:
            # On an error (or Ctrl-C) nothing waits for figures nobody will write.
            self._pool.shutdown(wait=exc is None, cancel_futures=exc is not None)
