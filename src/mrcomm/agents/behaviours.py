"""Registry of team behaviours: name -> executor class (SPEC §4).

Adding a behaviour is one module with a class registered by name::

    @register_behaviour("mine")
    class MyExecutor(TaskExecutor): ...
"""

from __future__ import annotations

from collections.abc import Callable

from mrcomm.agents.executor import TaskExecutor
from mrcomm.registry import Registry


def _load_builtin() -> None:
    # Behaviour modules register themselves on import; import them on first use.
    from mrcomm.agents import lf  # noqa: F401


BEHAVIOURS: Registry[type[TaskExecutor]] = Registry("behaviour", "behaviour", _load_builtin)


def register_behaviour(name: str) -> Callable[[type[TaskExecutor]], type[TaskExecutor]]:
    return BEHAVIOURS.register(name)


def behaviour_names() -> list[str]:
    return BEHAVIOURS.names()


def behaviour_class(name: str) -> type[TaskExecutor]:
    return BEHAVIOURS.get(name)


register_behaviour("nb")(TaskExecutor)
