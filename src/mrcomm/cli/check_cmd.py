"""``mrcomm check``: run the conformance kit (:mod:`mrcomm.testing`) on a variant —
yours from a plugin, or a built-in one — or on every registered variant."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from mrcomm.errors import InputError, did_you_mean


def check(
    variant: Annotated[
        str | None,
        typer.Argument(help="KIND.NAME (e.g. behaviour.lf), or NAME when it is unique."),
    ] = None,
    all_variants: Annotated[
        bool, typer.Option("--all", help="Check every registered variant.")
    ] = False,
    only: Annotated[
        list[str] | None, typer.Option("--only", help="Run only this check (repeatable).")
    ] = None,
    quiet: Annotated[
        bool, typer.Option("--quiet", help="No progress line (there is none when piped).")
    ] = False,
) -> None:
    """Check that a variant keeps the contract every variant must keep: API,
    determinism, no deadlock, same decisions on both buses, layering. Exit status 1
    when a check fails."""
    from mrcomm.cli.progress import ProgressLine
    from mrcomm.specs import KINDS, REGISTRY, VariantSpec, suggest
    from mrcomm.testing import CHECKS, check_variant

    for name in only or []:
        if name not in CHECKS:
            raise InputError(
                f"unknown check {name!r}{did_you_mean(name, CHECKS)}; checks: {', '.join(CHECKS)}",
                field="--only",
            )
    if all_variants == (variant is not None):
        raise InputError("give one VARIANT or --all", field="VARIANT")
    specs: list[VariantSpec]
    if all_variants:
        specs = REGISTRY.all()
    else:
        assert variant is not None
        kind, dot, name = variant.partition(".")
        if dot and kind in KINDS:
            specs = [REGISTRY.get(kind, name)]
        else:
            found = [s for s in REGISTRY.all() if s.name == variant]
            if len(found) != 1:
                keys = [s.key for s in REGISTRY.all()]
                why = "is ambiguous: give KIND.NAME" if found else "is not a variant"
                raise InputError(f"{variant!r} {why}{suggest(variant, REGISTRY.all())}; variants: "
                                 f"{', '.join(keys)}", field="VARIANT")  # fmt: skip
            specs = found
    console = Console()
    table = Table(title="Conformance")
    for column in ("variant", "check", "result", "s", "detail"):
        table.add_column(column, overflow="fold")
    failed = 0
    total = len(specs) * len([c for c in CHECKS if not only or c in only])
    started: list[str] = []
    with ProgressLine("check", total, enabled=not quiet) as line:
        for spec in specs:

            def starting(check: str, key: str = spec.key) -> None:
                done = len(started)
                started.append(check)
                line.update(done, f"{done}/{total} done · {key}: {check}")

            for result in check_variant(spec, only, starting):
                failed += not result.passed
                verdict = "[green]pass[/]" if result.passed else "[red]FAIL[/]"
                seconds = f"{result.seconds:.1f}"
                table.add_row(spec.key, result.check, verdict, seconds, result.detail)
    console.print(table)
    console.print(f"{failed} check(s) failed" if failed else "every check passed")
    raise typer.Exit(1 if failed else 0)
