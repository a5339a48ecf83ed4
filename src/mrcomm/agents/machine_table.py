"""The handler table of a behaviour's state machine, built and checked when the
executor class is created.

A behaviour's states are data (``states``: names, or nested definitions with
``children`` for a hierarchical machine). Every leaf state gets its entry once, from
those definitions — never by parsing state names at run time: its full name (as
``transitions`` names it), its path, its innermost and outermost state, and the method
that steps it: ``_step_<full name>`` if the class has one (``_step_leader_holding``),
else ``_step_<leaf>`` (NB's ``_step_navigating`` serves LF's ``leader_navigating``).
A leaf state without a handler must be declared passive; a ``_step_`` method that no
state uses is an error — both raised when the class is defined, not mid-mission.
(:func:`quiet_rebinding` keeps building a nested machine quiet.)
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

#: transitions' separator of nested state names (``NestedState.separator``).
SEPARATOR = "_"
HANDLER_PREFIX = "_step_"


@dataclass(frozen=True)
class StateEntry:
    full: str
    path: tuple[str, ...]
    #: The method stepping this state (None for a passive state).
    handler: Callable[[Any], None] | None

    @property
    def leaf(self) -> str:
        return self.path[-1]

    @property
    def top(self) -> str:
        return self.path[0]


def leaf_paths(states: Iterable[Any], prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """The path of every leaf state of ``states`` (transitions' state definitions)."""
    out: list[tuple[str, ...]] = []
    for state in states:
        if isinstance(state, str):
            out.append((*prefix, state))
        else:
            name = state["name"]
            children = state.get("children") or state.get("states")
            if children:
                out += leaf_paths(children, (*prefix, name))
            else:
                out.append((*prefix, name))
    return out


def build_table(cls: type, states: Iterable[Any], passive: frozenset[str]) -> dict[str, StateEntry]:
    """Each leaf state's entry; TypeError when a state lacks a handler or a handler
    names no state."""
    table: dict[str, StateEntry] = {}
    used: set[str] = set()
    for path in leaf_paths(states):
        full = SEPARATOR.join(path)
        handler = None
        for name in (f"{HANDLER_PREFIX}{full}", f"{HANDLER_PREFIX}{path[-1]}"):
            method = getattr(cls, name, None)
            if method is not None:
                handler = method
                used.add(name)
                break
        if handler is None and path[-1] not in passive:
            raise TypeError(
                f"{cls.__name__}: state {full!r} has no handler ({HANDLER_PREFIX}{full} or "
                f"{HANDLER_PREFIX}{path[-1]}); list {path[-1]!r} in PASSIVE_STATES if it needs none"
            )
        table[full] = StateEntry(full, path, handler)
    unused = sorted(
        name for name in dir(cls) if name.startswith(HANDLER_PREFIX) and name not in used
    )
    if unused:
        raise TypeError(f"{cls.__name__}: handlers for no state: {', '.join(unused)}")
    return table


@contextmanager
def quiet_rebinding() -> Iterator[None]:
    """Nested sub-machines share trigger names (``conflict``, ``resume``...); the first
    binding already dispatches on the current state, so transitions' warning that it
    skips re-binding them is noise. Silence it while a machine is built, only."""
    logger = logging.getLogger("transitions.core")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)
