"""SIGTERM and SIGINT as an exception a live process's loop ends on cleanly (its
journal closed, its session left), instead of dying where the signal found it."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any


class Stopped(Exception):
    """SIGTERM / SIGINT arrived: finish cleanly."""


@contextmanager
def stop_on_signals() -> Iterator[None]:
    """Within the block, SIGTERM and SIGINT raise :class:`Stopped`; the previous
    handlers come back after it. Off the main thread (a console's page runs the main
    thread and its signals) nothing changes."""

    def stop(signum: int, frame: FrameType | None) -> None:
        raise Stopped()

    previous: dict[signal.Signals, Any] = {}
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGTERM, signal.SIGINT):
            previous[sig] = signal.signal(sig, stop)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
