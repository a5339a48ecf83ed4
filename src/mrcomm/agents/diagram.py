"""State-machine diagrams of the behaviours, generated from the machines themselves
(the same ``states`` / ``transitions`` data the executors run)."""

from __future__ import annotations

import shutil
from typing import Any, Literal

from transitions.extensions.diagrams import HierarchicalGraphMachine

from mrcomm.agents.behaviours import behaviour_class


class _Model:
    """A bare model: the diagram needs the machine's structure, not an agent."""


def graphviz_available() -> bool:
    """Whether SVG/PNG rendering is possible (the ``dot`` program is installed)."""
    return shutil.which("dot") is not None


def behaviour_graph(behaviour: str, engine: Literal["graphviz", "mermaid"]) -> Any:
    """The transitions graph of a behaviour's machine (``engine``: graphviz|mermaid)."""
    cls = behaviour_class(behaviour)
    model = _Model()
    HierarchicalGraphMachine(
        model=model,
        states=cls.states,
        transitions=cls.transitions,
        initial=cls.initial,
        auto_transitions=False,
        graph_engine=engine,
        title=f"{behaviour.upper()} behaviour",
        show_conditions=False,
    )
    return model.get_graph()  # type: ignore[attr-defined]


def mermaid(behaviour: str) -> str:
    """Mermaid ``stateDiagram-v2`` text of a behaviour."""
    return str(behaviour_graph(behaviour, "mermaid").draw(None))


def render(behaviour: str, fmt: str) -> bytes:
    """SVG or PNG bytes of a behaviour's diagram through graphviz."""
    graph = behaviour_graph(behaviour, "graphviz")
    data = graph.draw(None, format=fmt, prog="dot")
    return data if isinstance(data, bytes) else str(data).encode()
