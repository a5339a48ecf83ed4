"""Name -> variant registries (behaviours, thresholds, utility functions, ...).

Adding a variant is one module with a decorated class or function; a duplicate name is
rejected; an unknown name is a one-line :class:`~mrcomm.errors.InputError` naming the
field, with a "did you mean" hint and the choices.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Generic, TypeVar

from mrcomm.errors import InputError, did_you_mean

T = TypeVar("T")


class Registry(Generic[T]):
    """Variants of one kind, by name."""

    def __init__(self, kind: str, field: str, load: Callable[[], object] | None = None) -> None:
        self.kind = kind
        self.field = field
        self._load = load  # imports the built-in variants' modules on first use
        self._entries: dict[str, T] = {}

    def register(self, name: str) -> Callable[[T], T]:
        def decorate(entry: T) -> T:
            if name in self._entries:
                raise ValueError(f"{self.kind} {name!r} registered twice")
            self._entries[name] = entry
            return entry

        return decorate

    def get(self, name: str) -> T:
        self._ensure_loaded()
        try:
            return self._entries[name]
        except KeyError:
            raise InputError(
                f"unknown {self.kind} {name!r}{did_you_mean(name, self._entries)}; "
                f"choose from {', '.join(sorted(self._entries))}",
                field=self.field,
            ) from None

    def names(self) -> list[str]:
        self._ensure_loaded()
        return sorted(self._entries)

    def _ensure_loaded(self) -> None:
        if self._load is not None:
            load, self._load = self._load, None
            load()
