"""Registry of team behaviours: name -> executor class (SPEC §4).

Adding a behaviour is one module with a class registered by name::

    @register_behaviour("mine")
    class MyExecutor(TaskExecutor): ...
"""

from __future__ import annotations

from collections.abc import Callable

from mrcomm.agents.executor import TaskExecutor
from mrcomm.errors import InputError, did_you_mean

_REGISTRY: dict[str, type[TaskExecutor]] = {}


def register_behaviour(name: str) -> Callable[[type[TaskExecutor]], type[TaskExecutor]]:
    def decorate(cls: type[TaskExecutor]) -> type[TaskExecutor]:
        if name in _REGISTRY:
            raise ValueError(f"behaviour {name!r} registered twice")
        _REGISTRY[name] = cls
        return cls

    return decorate


def behaviour_names() -> list[str]:
    _load_builtin()
    return sorted(_REGISTRY)


def behaviour_class(name: str) -> type[TaskExecutor]:
    _load_builtin()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise InputError(
            f"unknown behaviour {name!r}{did_you_mean(name, _REGISTRY)}; "
            f"choose from {', '.join(sorted(_REGISTRY))}",
            field="behaviour",
        ) from None


register_behaviour("nb")(TaskExecutor)


def _load_builtin() -> None:
    # Behaviour modules register themselves on import; import them on first use.
    from mrcomm.agents import lf  # noqa: F401
