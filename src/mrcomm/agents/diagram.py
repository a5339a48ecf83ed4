"""State-machine diagrams of the behaviours, generated from the machines themselves
(the same ``states`` / ``transitions`` data the executors run)."""

from __future__ import annotations

import re
import shutil
from typing import Any, Literal

from transitions.extensions.diagrams import HierarchicalGraphMachine

from mrcomm.agents.behaviours import behaviour_class


class _Model:
    """A bare model: the diagram needs the machine's structure, not an agent."""


class _DiagramMachine(HierarchicalGraphMachine):
    """The graph machine laid out top to bottom with room between nodes and ranks."""

    machine_attributes = {  # noqa: RUF012 (transitions reads it from the class)
        **HierarchicalGraphMachine.machine_attributes,
        "rankdir": "TB",
        "nodesep": "0.5",
        "ranksep": "0.7",
        "fontsize": "12",
        "forcelabels": "true",
    }


def graphviz_available() -> bool:
    """Whether SVG/PNG rendering is possible (the ``dot`` program is installed)."""
    return shutil.which("dot") is not None


def behaviour_graph(behaviour: str, engine: Literal["graphviz", "mermaid"]) -> Any:
    """The transitions graph of a behaviour's machine (``engine``: graphviz|mermaid)."""
    cls = behaviour_class(behaviour)
    model = _Model()
    _DiagramMachine(
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
    import graphviz

    source = behaviour_graph(behaviour, "graphviz").source
    # Edges into and out of a nested machine carry their name as a head/tail label,
    # which graphviz piles up where those edges meet: as a plain label it is placed
    # along the edge; a rank between the two ends gives opposite edges room to keep
    # their labels apart.
    source = re.sub(r"\b(head|tail)label=", "minlen=2 label=", source)
    data: bytes = graphviz.Source(source).pipe(format=fmt, engine="dot")
    return data
