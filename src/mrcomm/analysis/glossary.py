"""The glossary (docs/GLOSSARY.md: acronyms, metrics with units, statistics) as HTML
tables for the report, so a report read away from the repository still defines its
terms. The glossary ships inside the package (wheel) and is read from the checkout's
``docs/`` when MRComm runs from one."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from markupsafe import Markup, escape

import mrcomm

_PACKAGED = Path(mrcomm.__file__).resolve().parent / "GLOSSARY.md"
_CHECKOUT = Path(mrcomm.__file__).resolve().parents[2] / "docs" / "GLOSSARY.md"


@dataclass
class GlossarySection:
    #: The heading, with Markdown's inline code and emphasis as HTML.
    title: Markup
    columns: list[str] = field(default_factory=list)
    rows: list[list[Markup]] = field(default_factory=list)


def glossary_path() -> Path | None:
    """Where the glossary is (None: neither packaged nor in a checkout)."""
    for path in (_PACKAGED, _CHECKOUT):
        if path.is_file():
            return path
    return None


def _inline(text: str) -> Markup:
    """Markdown's inline code, bold and italics as HTML, everything else escaped."""
    html = str(escape(text.replace("\\|", "|")))
    html = re.sub(r"`([^`]+)`", r"<code>\1</code>", html)
    html = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", html)
    html = re.sub(r"\*([^*\s][^*]*)\*", r"<em>\1</em>", html)
    return Markup(html)


def _cells(line: str) -> list[str]:
    # Split on pipes that are not escaped (\|, as in |r|).
    inner = line.strip().strip("|")
    return [c.strip() for c in re.split(r"(?<!\\)\|", inner)]


def glossary_sections(path: Path | None = None) -> list[GlossarySection]:
    """The glossary's tables, one section per ``##`` heading."""
    path = path or glossary_path()
    if path is None:
        return []
    sections: list[GlossarySection] = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            sections.append(GlossarySection(_inline(line[3:].strip())))
        elif line.startswith("|") and sections:
            section = sections[-1]
            cells = _cells(line)
            if not section.columns:
                section.columns = cells
            elif not all(set(c) <= set("-: ") for c in cells):
                section.rows.append([_inline(c) for c in cells])
    return [s for s in [*sections, behaviour_metrics(sections)] if s.rows]


def behaviour_metrics(sections: list[GlossarySection]) -> GlossarySection:
    """The team metrics behaviours declare in their specs (plugins' too) that the
    glossary file does not define: name, unit, and what the spec calls it."""
    from mrcomm.specs import REGISTRY

    named = {str(row[0]) for s in sections for row in s.rows if row}
    section = GlossarySection(Markup("Metrics added by behaviours"))
    section.columns = ["metric", "unit", "meaning"]
    for spec in REGISTRY.all():
        for metric in spec.team_metrics:
            if not any(metric.name in cell for cell in named):
                named.add(metric.name)
                meaning = f"{metric.label} (behaviour {spec.name})"
                section.rows.append([escape(metric.name), escape(metric.unit), escape(meaning)])
    return section
