"""``mrcomm report``: a self-contained HTML report of a study (figures embedded,
tables, configuration, software version, date) plus every figure as PNG/SVG and every
table as CSV."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from mrcomm.errors import InputError
from mrcomm.output_paths import check_output_dir


def report(
    db: Annotated[
        Path, typer.Option(help="Results database (DuckDB): mrcomm sweep, or run/live --db.")
    ],
    out: Annotated[Path, typer.Option(help="Output directory (created if missing).")],
    metric: Annotated[
        list[str] | None,
        typer.Option(help="Metric to include (repeatable; default: every metric with data)."),
    ] = None,
    timeline: Annotated[
        list[str] | None,
        typer.Option(
            help="Run id whose timeline to draw (repeatable; default: one per behaviour)."
        ),
    ] = None,
    experiment: Annotated[
        str | None, typer.Option(help="Only the runs of this experiment.")
    ] = None,
    mode: Annotated[
        str | None,
        typer.Option(help="Only the runs of this mode: sim | live (needed when both are stored)."),
    ] = None,
    svg: Annotated[
        bool, typer.Option(help="Also write every figure as SVG and PDF (vector).")
    ] = True,
    alpha: Annotated[float, typer.Option(help="Significance level.")] = 0.05,
    correction: Annotated[
        str,
        typer.Option(help="Correction of p across the comparisons of the table: holm | bh | none."),
    ] = "holm",
    jobs: Annotated[
        int | None,
        typer.Option(help="Processes that encode the figures (default: one per CPU)."),
    ] = None,
    quiet: Annotated[
        bool, typer.Option("--quiet", help="No progress line (there is none when piped).")
    ] = False,
) -> None:
    """Write report.html, figures/*.png|svg|pdf and tables/*.csv into OUT."""
    # Imported here: matplotlib, scipy and DuckDB are not needed by the other commands.
    from mrcomm.analysis import report as rp
    from mrcomm.analysis import stats as st
    from mrcomm.analysis.encoding import available_cpus
    from mrcomm.analysis.inference import check_correction
    from mrcomm.cli.progress import ProgressLine

    if jobs is not None and jobs < 1:
        raise InputError(f"must be at least 1, got {jobs}", field="--jobs")
    if not 0 < alpha < 1:
        raise InputError(f"must be between 0 and 1, got {alpha:g}", field="--alpha")
    check_output_dir(out, "--out")
    method = check_correction(correction)
    st.resolve_metrics(metric)  # unknown metric: fail before loading anything
    with ProgressLine("report", None, enabled=not quiet, status="loading the results") as line:
        data = rp.load_study(db, experiment, mode)  # checks --mode before loading
        result = rp.build_report(
            data,
            out,
            db_path=db,
            metrics=metric,
            timeline_runs=timeline,
            svg=svg,
            alpha=alpha,
            correction=method,
            jobs=jobs or available_cpus(),
            progress=lambda status: line.update(None, status),
        )
    typer.echo(
        f"report: {result.html} ({len(result.figures)} figures, {len(result.tables)} tables, "
        f"{result.seconds:.1f} s)"
    )
