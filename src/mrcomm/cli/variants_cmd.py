"""``mrcomm variants``: every registered variant (behaviours, thresholds, network
models, utility functions — built-in and plugins) with its parameters, defaults and
units, like Gymnasium's registry listing."""

from __future__ import annotations

import json
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from mrcomm.specs import KINDS, VariantSpec


def describe(spec: VariantSpec) -> dict[str, Any]:
    """One variant as plain data: what ``--json`` prints and the table shows."""
    return {
        "kind": spec.kind,
        "name": spec.name,
        "version": spec.version,
        "summary": spec.summary,
        "origin": spec.origin,
        "network_types": sorted(spec.network_types) if spec.network_types else None,
        "topics": list(spec.topics),
        "metrics": list(spec.metrics),
        "uses_aon": spec.uses_aon,
        **({"accepts_reassignment": spec.accepts_reassignment} if spec.kind == "behaviour" else {}),
        "parameters": parameters(spec),
    }


def parameters(spec: VariantSpec) -> list[dict[str, Any]]:
    """Every settable parameter (``--set kind.key=``), nested models flattened."""
    schema = spec.params_model().model_json_schema()
    out: list[dict[str, Any]] = []

    def walk(node: dict[str, Any], prefix: str) -> None:
        for name, prop in node.get("properties", {}).items():
            ref = prop.get("$ref") or next(
                (a["$ref"] for a in prop.get("allOf", []) if "$ref" in a), None
            )
            if ref is not None:
                walk(schema["$defs"][ref.rsplit("/", 1)[-1]], f"{prefix}{name}.")
                continue
            out.append(
                {
                    "key": f"{spec.kind}.{prefix}{name}",
                    "default": prop.get("default"),
                    "unit": prop.get("unit"),
                    "type": _type_name(prop),
                    "description": prop.get("description", ""),
                }
            )

    walk(schema, "")
    return out


def _type_name(prop: dict[str, Any]) -> str:
    if "type" in prop:
        return str(prop["type"])
    options = [p.get("type", "?") for p in prop.get("anyOf", [])]
    return " | ".join(str(o) for o in options) or "?"


def variants(
    kind: Annotated[
        str | None, typer.Argument(help="Only this kind: behaviour, threshold, network, utility.")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON list.")] = False,
) -> None:
    """List every registered variant with its parameters, defaults and units."""
    from mrcomm.errors import InputError, did_you_mean
    from mrcomm.specs import REGISTRY

    if kind is not None and kind not in KINDS:
        raise InputError(
            f"unknown kind {kind!r}{did_you_mean(kind, KINDS)}; kinds: {', '.join(KINDS)}",
            field="KIND",
        )
    specs = [s for s in REGISTRY.all() if kind is None or s.kind == kind]
    rows = [describe(s) for s in specs]
    if as_json:
        typer.echo(json.dumps(rows, indent=2, default=str))
        return
    console = Console()
    for row in rows:
        title = f"{row['kind']} [bold]{row['name']}[/] v{row['version']}"
        if row["origin"] != "mrcomm":
            title += f" (plugin: {row['origin']})"
        console.print(title)
        console.print(f"  {row['summary']}", markup=False)
        needs = []
        if row["network_types"]:
            needs.append(f"networks: {', '.join(row['network_types'])}")
        if row["uses_aon"]:
            needs.append("statuses with AON")
        if row.get("accepts_reassignment") is False:
            needs.append("an operator may not reassign or add tasks")
        if needs:
            console.print("  " + "; ".join(needs), markup=False)
        if row["parameters"]:
            console.print(_parameter_table(row["parameters"]))
        console.print()


def _parameter_table(params: list[dict[str, Any]]) -> Table:
    """The parameters, their names and defaults never cut (users type them): on a
    narrow terminal the meaning column wraps instead."""
    table = Table(show_header=True, box=None, padding=(0, 1))
    keys = [p["key"] for p in params]
    defaults = [json.dumps(p["default"]) for p in params]
    table.add_column("parameter", no_wrap=True, min_width=max(map(len, keys)))
    table.add_column("default", no_wrap=True, min_width=max(map(len, defaults)))
    table.add_column("unit", no_wrap=True)
    table.add_column("meaning", overflow="fold", ratio=1, min_width=12)
    for p, default in zip(params, defaults, strict=True):
        table.add_row(p["key"], default, p["unit"] or "", p["description"])
    return table
