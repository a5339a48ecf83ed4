"""The one error type for bad input: it names the file, the field and what is wrong.

Every loader raises :class:`InputError`; the CLI turns it into a one-line message and
exit status 2, without a traceback.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from pathlib import Path


class InputError(Exception):
    """Bad user input: ``file: field: message``."""

    def __init__(self, message: str, *, file: str | Path | None = None, field: str | None = None):
        self.file = str(file) if file is not None else None
        self.field = field
        self.message = message
        super().__init__(self.one_line())

    def one_line(self) -> str:
        parts = [p for p in (self.file, self.field) if p]
        prefix = ": ".join(parts)
        text = f"{prefix}: {self.message}" if prefix else self.message
        return " ".join(text.split())


class MissionFailed(Exception):
    """A mission that could not go on, through no fault of the input (every agent
    process of a live team died; a live mission that never ended): the message says
    what happened and where to look (the CLI prints it in one line, exit status 1)."""


class Interrupted(Exception):
    """Ctrl-C, after the command has saved what it could: the message says what was
    kept (the CLI prints it in one line, exit status 130)."""


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """Return ' (did you mean 'x'?)' when a close match exists, else ''."""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""
