"""``mrcomm analyze``: the statistics tables of a study, printed as a terminal table
(fitting the terminal's width), CSV or LaTeX."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from mrcomm.errors import InputError, did_you_mean

FORMATS = ("table", "csv", "latex")


def analyze(
    db: Annotated[
        Path, typer.Option(help="Results database (DuckDB): mrcomm sweep, or run/live --db.")
    ],
    metric: Annotated[
        list[str] | None,
        typer.Option(help="Metric to test (repeatable; default: every metric with data)."),
    ] = None,
    fmt: Annotated[str, typer.Option("--format", help="Output: table | csv | latex.")] = "table",
    table: Annotated[
        list[str] | None,
        typer.Option(
            help="Table to print (repeatable): comparisons, normality, descriptive, "
            "success_counts, success_tests, rssi, between, pairwise (default: all)."
        ),
    ] = None,
    experiment: Annotated[
        str | None, typer.Option(help="Only the runs of this experiment.")
    ] = None,
    mode: Annotated[
        str | None,
        typer.Option(help="Only the runs of this mode: sim | live (needed when both are stored)."),
    ] = None,
    alpha: Annotated[float, typer.Option(help="Significance level.")] = 0.05,
    correction: Annotated[
        str,
        typer.Option(help="Correction of p across the comparisons of the table: holm | bh | none."),
    ] = "holm",
) -> None:
    """Print the statistics of a study: Mann–Whitney SPL0 vs SPLX, Shapiro–Wilk,
    descriptive statistics, mission-success contingency tables and, with several
    behaviours, Kruskal–Wallis and pairwise Mann–Whitney between them."""
    # Imported here: scipy, pandas and DuckDB are not needed by the other commands.
    from mrcomm.analysis import report as rp
    from mrcomm.analysis import stats as st
    from mrcomm.analysis import table_format as tf
    from mrcomm.analysis.figures_report import metrics_with_data
    from mrcomm.analysis.inference import check_correction
    from mrcomm.analysis.study import study_tables

    if fmt not in FORMATS:
        raise InputError(
            f"unknown format {fmt!r}{did_you_mean(fmt, FORMATS)}; choose table, csv or latex",
            field="--format",
        )
    if not 0 < alpha < 1:
        raise InputError(f"must be between 0 and 1, got {alpha:g}", field="--alpha")
    method = check_correction(correction)
    names = _tables(table)
    st.resolve_metrics(metric)  # unknown metric: fail before loading anything
    data = rp.load_study(db, experiment, mode)  # checks --mode before loading
    runs = data.runs
    rp.check_runs(runs, db)
    tables = study_tables(
        runs,
        metrics_with_data(runs, metric),
        alpha,
        method,
        rssi=data.rssi,
        trajectories=data.trajectories,
    )
    console = Console() if fmt == "table" else None
    if console is not None and rp.study_mode(runs) == "live":
        console.print("[bold]Live runs[/] (every agent its own process over Zenoh)")
    for i, name in enumerate(names):
        frame = tables.get(name)
        if fmt == "csv":
            # Full precision, one block per table, separated by a comment line.
            typer.echo(f"# {name}")
            typer.echo(frame.to_csv(index=False), nl=False)
        elif fmt == "latex":
            typer.echo(tf.to_latex(name, frame), nl=False)
        else:
            assert console is not None
            if name == "comparisons":
                _print_comparisons(console, frame, tf, st, method, alpha)
            elif name == "rssi":
                _print_rssi(console, frame, tf)
            elif name in ("between", "pairwise"):
                _print_between(console, name, frame, tf, st)
            else:
                shown = tf.display_frame(name, frame)
                console.print(_rich_table(tf.TABLE_TITLES[name], shown))
        if i < len(names) - 1 and fmt != "table":
            typer.echo("")


def _tables(names: list[str] | None) -> list[str]:
    from mrcomm.analysis.study import TABLE_NAMES

    if not names:
        return list(TABLE_NAMES)
    for name in names:
        if name not in TABLE_NAMES:
            hint = did_you_mean(name, TABLE_NAMES)
            raise InputError(
                f"unknown table {name!r}{hint}; known: {', '.join(TABLE_NAMES)}", field="--table"
            )
    return names


def _print_comparisons(
    console: Console, frame: Any, tf: Any, st: Any, method: str, alpha: float
) -> None:
    """The comparisons, one table per metric (the terminal's width is the limit)."""
    console.print(f"[bold]{tf.TABLE_TITLES['comparisons']}[/]")
    for metric, rows in frame.groupby("metric", sort=False):
        info = st.metric_info(str(metric))
        title = f"{info.label} ({info.unit})"
        console.print(_rich_table(title, tf.display_frame("comparisons", rows, compact=True)))
    if frame.empty:
        console.print("no comparisons")
    console.print(
        f"p corr.: p corrected across all {len(frame)} comparisons "
        f"({tf.CORRECTION_NAMES[method]}); † the design cannot reach α = {alpha:g}. "
        "All columns (U, Z, raw p, means, the original r = Z/√n): --format csv or latex.",
        style="dim",
    )
    for warning in st.unreachable(frame, alpha):
        console.print(f"warning: {warning}", style="yellow", markup=False)


def _print_between(console: Console, name: str, frame: Any, tf: Any, st: Any) -> None:
    """A between-behaviour table, one per metric; nothing when the study has one
    behaviour."""
    if frame.empty:
        return
    console.print(f"[bold]{tf.TABLE_TITLES[name]}[/]")
    for metric, rows in frame.groupby("metric", sort=False):
        info = st.metric_info(str(metric))
        shown = tf.display_frame(name, rows, compact=True)
        console.print(_rich_table(f"{info.label} ({info.unit})", shown))


def _print_rssi(console: Console, frame: Any, tf: Any) -> None:
    """SSD vs ESD, one table per pair of thresholds compared."""
    from mrcomm.analysis.rssi_compare import compared_pairs

    if frame.empty:
        console.print(f"[bold]{tf.TABLE_TITLES['rssi']}[/]")
        console.print("no two configurations differing only in their threshold recorded RSSI")
        return
    groups = frame.groupby(["threshold_a", "threshold_b"], sort=False)
    for pair, (_, rows) in zip(compared_pairs(frame), groups, strict=True):
        title = f"{tf.TABLE_TITLES['rssi']}: {pair}"
        console.print(_rich_table(title, tf.display_frame("rssi", rows, compact=True)))
    console.print(
        "shift: Hodges–Lehmann median of the per-run differences (first − second), dBm; "
        "at D m (a-b m): the readings taken while the two robots were a-b m apart, moved "
        "to D m along one log-distance slope fitted to both. "
        "All columns (U, Z, raw p, r): --format csv or latex.",
        style="dim",
    )


def _rich_table(title: str, frame: object) -> Table:
    import pandas as pd

    assert isinstance(frame, pd.DataFrame)
    from mrcomm.analysis.stats import SUPPORTED

    out = Table(title=title, title_justify="left")
    for column in frame.columns:
        # Cells wrap rather than lose characters to an ellipsis.
        text = column in _TEXT
        out.add_column(
            str(column),
            justify="left" if text else "right",
            overflow="fold",
            no_wrap=column == "decision",  # the verdict is read whole
        )
    decisions = frame["decision"] if "decision" in frame.columns else [None] * len(frame)
    for row, decision in zip(frame.itertuples(index=False), decisions, strict=True):
        out.add_row(*(str(c) for c in row), style="green" if decision == SUPPORTED else None)
    if frame.empty:
        out.caption = "no rows"
    return out


_TEXT = {
    *("metric", "configuration", "config", "H_A", "effect", "decision", "direction"),
    "median SPL0 → SPLX",
    *("method", "comparison", "note"),
}
