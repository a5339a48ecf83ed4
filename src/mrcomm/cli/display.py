"""How the CLI shows values in its tables (one convention for every command)."""

from __future__ import annotations

from typing import Any


def fmt(value: Any) -> str:
    """Floats to 2 decimals, lists joined ("none" when empty), None as "-"."""
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.2f}"
    if isinstance(value, list):
        return ", ".join(map(str, value)) or "none"
    return str(value)
