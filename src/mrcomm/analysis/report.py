"""The report of a study: from a results database to a self-contained HTML page
(figures embedded as base64 PNG, tables, configuration, software versions, date), plus
every figure as PNG and SVG and every table as CSV (the tables formatted by
:mod:`mrcomm.analysis.table_format`).

Nothing is written until everything has been computed, and each file is written
atomically: a failure leaves no half-written report behind.
"""

from __future__ import annotations

import datetime as dt
import platform
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import jinja2
import pandas as pd

import mrcomm
from mrcomm.analysis import stats as st
from mrcomm.analysis.figures_comm import message_table
from mrcomm.analysis.figures_report import (
    build_figures,
    constant_metrics,
    frame_of,
    metrics_with_data,
    pick_timeline_runs,
)
from mrcomm.analysis.glossary import glossary_sections
from mrcomm.analysis.inference import Correction
from mrcomm.analysis.report_provenance import config_rows, provenance_rows
from mrcomm.analysis.settings import with_settings
from mrcomm.analysis.study import TABLE_NAMES, study_tables
from mrcomm.analysis.table_format import (
    CORRECTION_NAMES,
    TABLE_TITLES,
    config_label,
    display_frame,
    fmt_num,
    is_number,
)
from mrcomm.errors import InputError
from mrcomm.experiment.tables import RUN_MODES
from mrcomm.fileio import atomic_write_bytes
from mrcomm.net.delivery import DROP_CAUSES, DROPPED_COLLISION, RADIO_COUNT_KEYS, count_keys


def _check_mode(mode: str | None) -> None:
    if mode is not None and mode not in RUN_MODES:
        raise InputError(f"unknown mode {mode!r}; choose sim or live", field="--mode")


def load_study(db_path: Path, experiment: str | None = None, mode: str | None = None) -> Any:
    """The results database at ``db_path`` (``mrcomm.experiment.api.load_results``),
    optionally only one experiment's runs, and only the runs of one ``mode``.

    Simulated and live runs are never pooled: the statistics group runs by scenario,
    network, threshold, behaviour and SPL, which both modes share. A database holding
    both is refused unless ``mode`` picks one."""
    _check_mode(mode)
    if not db_path.is_file():
        raise InputError("no such results database", file=db_path, field="--db")
    from mrcomm.experiment.api import load_results

    try:
        data = load_results(db_path, experiment, mode)
    except InputError:
        raise
    except Exception as err:  # duckdb raises its own types for a file that is not a DB
        raise InputError(f"not a results database ({err})", file=db_path, field="--db") from err
    modes = sorted(str(m) for m in data.runs["mode"].dropna().unique())
    if mode is None and len(modes) > 1:
        data.close()
        raise InputError(
            f"the runs are of several modes ({', '.join(modes)}), which must not be pooled: "
            "pick one with --mode sim or --mode live",
            file=db_path,
            field="--mode",
        )
    if mode is not None and data.runs.empty:
        data.close()
        raise InputError(f"the database has no {mode} runs", file=db_path, field="--mode")
    data.runs = with_settings(data.runs, data.configs)
    return data


def study_mode(runs: pd.DataFrame) -> str | None:
    """The one mode of a study's runs (None when unknown or mixed)."""
    modes = runs["mode"].dropna().unique() if "mode" in runs else []
    return str(modes[0]) if len(modes) == 1 else None


def check_runs(runs: pd.DataFrame, db_path: Path | None) -> None:
    """A study needs at least one finished run."""
    if runs.empty:
        raise InputError("the database has no runs", file=db_path, field="runs")
    if st.usable_runs(runs).empty:
        raise InputError(
            f"none of the {len(runs)} runs finished (status ok)", file=db_path, field="runs"
        )


# ---- the report ----------------------------------------------------------------------------


@dataclass
class Report:
    """What :func:`build_report` wrote."""

    out_dir: Path
    html: Path
    figures: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    seconds: float = 0.0


def _meta(data: Any) -> dict[str, str]:
    meta = getattr(data, "meta", None)
    if isinstance(meta, dict):
        return {str(k): str(v) for k, v in meta.items()}
    con = getattr(data, "con", None)
    if con is None:
        return {}
    try:
        return {str(k): str(v) for k, v in con.execute("SELECT key, value FROM meta").fetchall()}
    except Exception:  # an old or partial database without meta: report without it
        return {}


def _package_versions() -> dict[str, str]:
    out = {"mrcomm": mrcomm.__version__, "python": platform.python_version()}
    for pkg in ("numpy", "scipy", "pandas", "matplotlib", "duckdb"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def _count_keys(table: pd.DataFrame) -> list[str]:
    """The count columns to show: the radio's only when some run had a radio, the
    collisions only when some run had the shared channel."""
    radio = not table.empty and bool(table[list(RADIO_COUNT_KEYS)].to_numpy().sum() > 0)
    shared = not table.empty and bool(table[DROPPED_COLLISION].sum() > 0)
    return count_keys(radio, shared)


def _message_columns(runs: pd.DataFrame, messages: pd.DataFrame) -> list[str]:
    table = message_table(runs, messages)
    causes = [DROP_CAUSES[k] for k in _count_keys(table) if k in DROP_CAUSES]
    return ["configuration", "SPL", "topic", "runs", "sent", "received", *causes, "not received %"]


def _message_rows(runs: pd.DataFrame, messages: pd.DataFrame) -> list[list[str]]:
    """Mean messages per run, by configuration, SPL level and topic (the table next to
    the figure of messages lost)."""
    table = message_table(runs, messages)
    if table.empty:
        return []
    multi = table["scenario"].nunique() > 1
    return [
        [
            config_label(row, multi),
            f"{float(row['spl']):g}",
            str(row["topic"]),
            str(int(row["runs"])),
            *(fmt_num(row[k], 1) for k in _count_keys(table)),
            fmt_num(row["lost_percent"], 1),
        ]
        for _, row in table.iterrows()
    ]


def _failed_runs(runs: pd.DataFrame) -> list[list[str]]:
    bad = runs[runs["status"] != "ok"] if "status" in runs else runs.iloc[0:0]
    return bad.reindex(columns=["run_id", "status", "error"]).fillna("").astype(str).values.tolist()


def _html_table(name: str, frame: pd.DataFrame) -> dict[str, Any]:
    shown = display_frame(name, frame)
    shaded = name in ("comparisons", "between", "pairwise")
    decided = frame["decision"].tolist() if shaded else [""] * len(frame)
    rows = [
        {"cells": [(c, is_number(c)) for c in cells], "cls": "sig" if flag == st.SUPPORTED else ""}
        for cells, flag in zip(shown.values.tolist(), decided, strict=True)
    ]
    return {"columns": list(shown.columns), "rows": rows}


def build_report(
    data: Any,
    out_dir: Path,
    *,
    db_path: Path | None = None,
    metrics: Sequence[str] | None = None,
    timeline_runs: Sequence[str] | None = None,
    svg: bool = True,
    alpha: float = st.ALPHA,
    correction: Correction = "holm",
    jobs: int = 1,
    progress: Callable[[str], None] | None = None,
) -> Report:
    """Compute tables and figures of ``data`` (a ``load_results`` Results) and write the
    report into ``out_dir`` (created if missing): report.html, figures/, tables/.
    ``jobs`` processes encode the figures; ``progress`` is told what is being done."""
    tell = progress or (lambda _: None)
    started = time.perf_counter()
    runs = frame_of(data, "runs")
    check_runs(runs, db_path)
    chosen = metrics_with_data(runs, metrics)
    tell(f"statistics of {len(chosen)} metrics")
    tables = study_tables(
        runs,
        chosen,
        alpha,
        correction,
        rssi=frame_of(data, "rssi"),
        trajectories=frame_of(data, "trajectories"),
    )
    timelines = pick_timeline_runs(runs, timeline_runs)
    figures = build_figures(data, chosen, timelines, svg, jobs, progress)
    tell(f"writing {out_dir}")
    status = runs["status"].value_counts().to_dict() if "status" in runs else {}
    meta = _meta(data)
    # The runs' own experiment when they have one (meta names only the latest sweep).
    names = runs["experiment"].dropna().unique() if "experiment" in runs else []
    name = str(names[0]) if len(names) == 1 else meta.get("experiment", "") or db_path or ""
    title = f"MRComm study report: {name}".strip()
    if study_mode(runs) == "live":
        title += " (live runs: every agent its own process over Zenoh)"
    context = {
        "title": title,
        "generated": dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M:%S UTC"),
        "db_path": str(db_path) if db_path else "",
        "meta": {k: v for k, v in meta.items() if k != "schema_yaml"},
        "schema_yaml": meta.get("schema_yaml", ""),
        "versions": _package_versions(),
        "alpha": alpha,
        "correction": CORRECTION_NAMES[correction],
        "design_warnings": st.unreachable(tables.comparisons, alpha),
        "n_runs": len(runs),
        "status": status,
        "errors": _failed_runs(runs),
        "provenance": provenance_rows(runs),
        "configs": config_rows(frame_of(data, "configs")),
        "config_columns": [
            *(c for c in frame_of(data, "configs").columns if c != "options"),
            "parameters",
            "variants",
        ],
        "tables": {name: _html_table(name, tables.get(name)) for name in TABLE_NAMES},
        "table_titles": TABLE_TITLES,
        "figures": figures,
        "constant": constant_metrics(runs, chosen),
        "messages": _message_rows(runs, frame_of(data, "messages")),
        "message_columns": _message_columns(runs, frame_of(data, "messages")),
        "glossary": glossary_sections(),
    }
    html = _environment().get_template("report.html.j2").render(**context)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "figures").mkdir(exist_ok=True)
    (out_dir / "tables").mkdir(exist_ok=True)
    report = Report(out_dir=out_dir, html=out_dir / "report.html")
    written: set[str] = set()
    for section in figures.values():
        for f in section:
            _write(out_dir / "figures" / f"{f.id}.png", f.png)
            written.add(f"{f.id}.png")
            for suffix, payload in (("svg", f.svg), ("pdf", f.pdf)):
                if payload is not None:
                    _write(out_dir / "figures" / f"{f.id}.{suffix}", payload)
                    written.add(f"{f.id}.{suffix}")
            report.figures.append(f.id)
    # Written over an older report: its figures that this one does not have would be
    # taken for part of it. figures/ holds only what reports write.
    for old in (out_dir / "figures").glob("*"):
        if old.suffix in (".png", ".svg", ".pdf") and old.name not in written:
            old.unlink()
    for name in TABLE_NAMES:
        _write(out_dir / "tables" / f"{name}.csv", tables.get(name).to_csv(index=False).encode())
        report.tables.append(name)
    _write(report.html, html.encode("utf-8"))
    report.seconds = time.perf_counter() - started
    return report


def _write(path: Path, payload: bytes) -> None:
    """Write via a temporary file and a rename, so no reader sees a partial file."""
    atomic_write_bytes(path, payload)


def _environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(Path(__file__).parent / "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
