"""`mrcomm fsm`: diagrams generated from the behaviour machines."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrcomm.agents.diagram import mermaid
from tests import needs
from tests.cli.test_run_cli import mrcomm


def test_mermaid_text_lists_the_nested_states(tmp_path: Path) -> None:
    out = tmp_path / "lf.mmd"
    proc = mrcomm("fsm", "--behaviour", "lf", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    text = out.read_text()
    assert "stateDiagram-v2" in text
    for state in (
        "na_navigating",
        "leader_holding",
        "follower_following",
        "assigning",
        "regrouping",
    ):
        assert state in text, state
    assert "disconnect" in text and "dissolve" in text


def test_nb_diagram_has_only_nb_states() -> None:
    text = mermaid("nb")
    assert "navigating" in text and "avoiding" in text
    assert "leader" not in text


@needs.needs_commands("dot")
def test_svg_through_graphviz(tmp_path: Path) -> None:
    out = tmp_path / "lf.svg"
    proc = mrcomm("fsm", "--behaviour", "lf", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    svg = out.read_text()
    assert svg.lstrip().startswith("<?xml") or "<svg" in svg[:500]
    assert "holding" in svg and "following" in svg


def test_bad_behaviour_or_format_exits_2(tmp_path: Path) -> None:
    proc = mrcomm("fsm", "--behaviour", "lff", "--out", str(tmp_path / "x.svg"))
    assert proc.returncode == 2 and "did you mean 'lf'" in proc.stderr
    proc = mrcomm("fsm", "--out", str(tmp_path / "x.gif"))
    assert proc.returncode == 2 and ".gif" in proc.stderr
    assert not any(tmp_path.iterdir())


@needs.needs_commands("dot")
@pytest.mark.parametrize("behaviour", ["lf", "nb"])
def test_edge_labels_do_not_overlap(behaviour: str) -> None:
    """Every label of the SVG diagram, boxed by its position, font size and length
    (a generous 0.55 em per character), overlaps no other label."""
    import re

    from mrcomm.agents.diagram import render

    svg = render(behaviour, "svg").decode()
    boxes = []
    for match in re.finditer(
        r'<text text-anchor="(\w+)" x="([-\d.]+)" y="([-\d.]+)"[^>]*font-size="([\d.]+)"[^>]*>'
        r"([^<]+)</text>",
        svg,
    ):
        anchor, x, y, size, text = match.groups()
        width = 0.55 * float(size) * len(text)
        left = float(x) - {"start": 0.0, "middle": width / 2, "end": width}[anchor]
        boxes.append((text, left, float(y) - float(size) * 0.8, width, float(size) * 0.9))
    assert len(boxes) > 20
    clashes = [
        (a[0], b[0])
        for i, a in enumerate(boxes)
        for b in boxes[i + 1 :]
        if a[1] < b[1] + b[3] and b[1] < a[1] + a[3] and a[2] < b[2] + b[4] and b[2] < a[2] + a[4]
    ]
    assert clashes == []
