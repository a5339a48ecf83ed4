"""Compiling the hot loops: numba's ``njit`` when it is installed (the ``fast`` extra, in
the development install), the plain Python functions otherwise.

The loops that are compiled (ray casts: :mod:`mrcomm.world.traversal`; the shared radio
channel: :mod:`mrcomm.net.radio.air`) are written as plain Python over numpy arrays and
scalars, so that either way they compute the same IEEE double arithmetic in the same
order (no fast-math) and give the same answers. Set ``MRCOMM_NO_NUMBA=1`` to run the
plain functions even where numba is installed.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


def _numba_jit() -> Callable[[Any], Any] | None:
    if os.environ.get("MRCOMM_NO_NUMBA"):
        return None
    try:
        import numba  # type: ignore[import-untyped,unused-ignore]
    except ImportError:
        return None
    # error_model="numpy": a division by zero gives inf/NaN as in numpy, not an
    # exception (the compiled loops guard their divisions anyway).
    jit: Callable[[Any], Any] = numba.njit(cache=True, nogil=True, error_model="numpy")
    return jit


_JIT = _numba_jit()

#: What runs the compiled loops: "numba" or "python".
KERNEL = "numba" if _JIT is not None else "python"


def compiled(func: F) -> F:
    """``func`` compiled by numba, or ``func`` itself without it."""
    if _JIT is None:
        return func
    jitted: F = _JIT(func)
    return jitted
