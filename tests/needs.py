"""Skips for what ``make test`` installs (system tools through ``make system-deps``,
Python packages through the ``dev`` extra, the ROS 2 environment): their reasons carry
:data:`TAG`, and with ``MRCOMM_REQUIRE_ALL=1`` (set by ``.ci/run``) the session fails
when any such skip happened (``tests/conftest.py``), so a green CI run means every test
ran. Skips a machine legitimately causes (not root, asked to skip) carry no tag."""

from __future__ import annotations

import importlib
import os
import shutil
from types import ModuleType

import pytest

#: Marks a skip for something ``make test`` installs.
TAG = "[make test installs it]"
REQUIRE_ALL = os.environ.get("MRCOMM_REQUIRE_ALL") == "1"


def reason(text: str) -> str:
    """A skip reason for something ``make test`` installs."""
    return f"{text} {TAG}"


def missing_commands(*commands: str) -> str | None:
    """The skip reason when one of ``commands`` is not on PATH (None: all are)."""
    absent = [c for c in commands if shutil.which(c) is None]
    if not absent:
        return None
    return reason(f"{', '.join(absent)} not installed (make system-deps installs it as root)")


def needs_commands(*commands: str) -> pytest.MarkDecorator:
    """A skip mark for a test that runs ``commands``."""
    why = missing_commands(*commands)
    return pytest.mark.skipif(why is not None, reason=why or "")


def module(name: str, extra: str = "dev") -> ModuleType:
    """``pytest.importorskip`` for a package one of the project's extras installs."""
    try:
        return importlib.import_module(name)
    except ImportError as err:
        pytest.skip(reason(f"{name} not installed (the [{extra}] extra): {err}"),
                    allow_module_level=True)  # fmt: skip


def is_required_skip(longrepr: object) -> bool:
    """Whether a skip report's reason is one of ours (its longrepr is a
    (file, line, reason) tuple for skips)."""
    text = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else longrepr
    return TAG in str(text)
