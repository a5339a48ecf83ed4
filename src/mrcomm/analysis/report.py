"""The report of a study: from a results database to a self-contained HTML page
(figures embedded as base64 PNG, tables, configuration, software versions, date), plus
every figure as PNG and SVG and every table as CSV. Also the human formatting of the
statistics tables, shared with ``mrcomm analyze`` (terminal, LaTeX).

Nothing is written until everything has been computed, and each file is written
atomically: a failure leaves no half-written report behind.
"""

from __future__ import annotations

import datetime as dt
import math
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
from mrcomm.errors import InputError
from mrcomm.experiment.tables import RUN_MODES
from mrcomm.fileio import atomic_write_bytes
from mrcomm.net.delivery import DROP_CAUSES, RADIO_COUNT_KEYS, count_keys

TABLE_TITLES = {
    "comparisons": "Mann-Whitney U, SPL0 vs SPLX (one-sided; p corrected across the table)",
    "normality": "Shapiro-Wilk normality per sample",
    "descriptive": "Descriptive statistics per configuration",
    "success_counts": "Successful missions (contingency tables)",
    "success_tests": "Chi-squared tests of mission success",
    "rssi": "RSSI seen under two thresholds (Mann-Whitney U per run, two-sided; "
    "p corrected across the table)",
    "between": "Between behaviours: Kruskal-Wallis per condition (p corrected across the table)",
    "pairwise": "Between behaviours: pairwise Mann-Whitney U (two-sided; Holm within each "
    "condition's pairs)",
}


#: How the report names each p-value correction.
CORRECTION_NAMES = {
    "holm": "Holm (family-wise error rate)",
    "bh": "Benjamini–Hochberg (false discovery rate)",
    "none": "none",
}


# ---- human formatting of the tables ------------------------------------------------------


def fmt_p(p: Any) -> str:
    if p is None or not math.isfinite(float(p)):
        return "–"
    return "<0.0001" if float(p) < 1e-4 else f"{float(p):.4f}"


def fmt_num(x: Any, digits: int = 2) -> str:
    if x is None or not math.isfinite(float(x)):
        return "–"
    return f"{float(x):.{digits}f}"


def _mean_sd(mean: Any, sd: Any) -> str:
    if mean is None or not math.isfinite(float(mean)):
        return "–"
    return f"{float(mean):.2f}" + ("" if not math.isfinite(float(sd)) else f" ± {float(sd):.2f}")


def _median_iqr(median: Any, iqr: Any) -> str:
    if median is None or not math.isfinite(float(median)):
        return "–"
    return f"{float(median):.2f} [{float(iqr):.2f}]"


def _r_ci(r: pd.Series) -> str:
    text = fmt_num(r["r"], 2)
    if math.isfinite(float(r["r_low"])):
        text += f" [{float(r['r_low']):.2f}, {float(r['r_high']):.2f}]"
    return text


def _p_adj(r: pd.Series) -> str:
    flag = "" if bool(r["reachable"]) or not math.isfinite(float(r["min_p"])) else " †"
    return fmt_p(r["p_adj"]) + flag


def _config(r: pd.Series, multi: bool) -> str:
    parts = [str(r["network"]).upper()]
    if str(r["threshold"]) != "none":
        parts.append(str(r["threshold"]).upper())
    parts.append(str(r["behaviour"]).upper())
    text = "+".join(parts) + (f" ({r['setting']})" if str(r.get("setting", "")) else "")
    return (f"{r['scenario']} " if multi else "") + text


def _condition(r: pd.Series, multi: bool) -> str:
    """A between-behaviour condition: network, threshold, SPL and setting."""
    parts = [str(r["network"]).upper()]
    if str(r["threshold"]) != "none":
        parts.append(str(r["threshold"]).upper())
    text = "+".join(parts) + f" SPL{float(r['spl']):g}"
    text += f" ({r['setting']})" if str(r.get("setting", "")) else ""
    return (f"{r['scenario']} " if multi else "") + text


def _method(m: Any) -> str:
    text = str(m)
    return "exact perm." if text.startswith("exact perm") else text.split(" ")[0]


Column = tuple[str, Callable[[pd.Series, bool], str]]
_CFG: Column = ("configuration", _config)
_SPL: Column = ("SPL", lambda r, _: f"{float(r['spl']):g}")
_COLUMNS: dict[str, list[Column]] = {
    "comparisons": [
        ("metric", lambda r, _: str(r["metric"])),
        _CFG,
        ("H_A", lambda r, _: str(r["hypothesis"])),
        ("m", lambda r, _: str(r["m"])),
        ("n", lambda r, _: str(r["n"])),
        ("SPL0 median [IQR]", lambda r, _: _median_iqr(r["median0"], r["iqr0"])),
        ("SPLX median [IQR]", lambda r, _: _median_iqr(r["median_x"], r["iqr_x"])),
        ("SPL0 mean ± SD", lambda r, _: _mean_sd(r["mean0"], r["sd0"])),
        ("SPLX mean ± SD", lambda r, _: _mean_sd(r["mean_x"], r["sd_x"])),
        ("U (SPL0)", lambda r, _: fmt_num(r["u"], 1)),
        ("Z", lambda r, _: fmt_num(r["z"], 2)),
        ("p", lambda r, _: fmt_p(r["p"])),
        ("p corr.", lambda r, _: _p_adj(r)),
        ("r=Z/√(m+n) [95% CI]", lambda r, _: _r_ci(r)),
        ("effect", lambda r, _: str(r["effect"])),
        ("direction", lambda r, _: str(r["direction"])),
        ("r=Z/√n (original)", lambda r, _: fmt_num(r["r_original"], 2)),
        ("decision", lambda r, _: str(r["decision"])),
        ("method", lambda r, _: _method(r["method"])),
    ],
    "normality": [
        ("metric", lambda r, _: str(r["metric"])),
        _CFG,
        _SPL,
        ("n", lambda r, _: str(r["n"])),
        ("W", lambda r, _: fmt_num(r["w"], 4)),
        ("p", lambda r, _: fmt_p(r["p"])),
        ("normal (p ≥ α)", lambda r, _: str(r["normal"])),
    ],
    "descriptive": [
        ("metric", lambda r, _: str(r["metric"])),
        _CFG,
        _SPL,
        ("n", lambda r, _: str(r["n"])),
        ("mean [95% CI]", lambda r, _: _with_ci(r, "mean")),
        ("SD", lambda r, _: fmt_num(r["sd"])),
        ("median [95% CI]", lambda r, _: _with_ci(r, "median")),
        ("IQR", lambda r, _: fmt_num(float(r["q3"]) - float(r["q1"]))),
        ("min", lambda r, _: fmt_num(r["min"])),
        ("max", lambda r, _: fmt_num(r["max"])),
    ],
    "success_counts": [
        _CFG,
        _SPL,
        *((k, (lambda key: lambda r, _: str(r[key]))(k)) for k in ("runs", "successful", "failed")),
        ("successful %", lambda r, _: fmt_num(r["percent"], 1)),
    ],
    "success_tests": [
        _CFG,
        ("comparison", lambda r, _: str(r["comparison"])),
        ("χ²", lambda r, _: fmt_num(r["chi2"], 3)),
        ("dof", lambda r, _: str(r["dof"])),
        ("p", lambda r, _: fmt_p(r["p"])),
        ("Fisher p", lambda r, _: fmt_p(r["fisher_p"])),
        ("min expected", lambda r, _: fmt_num(r["min_expected"], 2)),
        ("note", lambda r, _: str(r["note"])),
    ],
    "between": [
        ("metric", lambda r, _: str(r["metric"])),
        ("condition", _condition),
        ("behaviours", lambda r, _: str(r["behaviours"])),
        ("medians", lambda r, _: str(r["medians"])),
        ("N", lambda r, _: str(r["n"])),
        ("H", lambda r, _: fmt_num(r["h"], 2)),
        ("df", lambda r, _: str(r["df"])),
        ("p", lambda r, _: fmt_p(r["p"])),
        ("p corr.", lambda r, _: fmt_p(r["p_adj"])),
        ("ε²", lambda r, _: fmt_num(r["epsilon2"], 2)),
        ("decision", lambda r, _: str(r["decision"])),
    ],
    "pairwise": [
        ("metric", lambda r, _: str(r["metric"])),
        ("condition", _condition),
        ("A vs B", lambda r, _: f"{r['behaviour_a']} vs {r['behaviour_b']}"),
        ("medians", lambda r, _: _medians_ab(r)),
        ("m/n", lambda r, _: f"{r['m']}/{r['n']}"),
        ("p", lambda r, _: fmt_p(r["p"])),
        ("p Holm", lambda r, _: fmt_p(r["p_adj"])),
        ("r=Z/√(m+n) [95% CI]", lambda r, _: _r_ci(r)),
        ("effect", lambda r, _: str(r["effect"])),
        ("direction", lambda r, _: str(r["direction"])),
        ("decision", lambda r, _: str(r["decision"])),
    ],
    "rssi": [
        ("configuration", lambda r, multi: _rssi_config(r, multi)),
        ("SPL", lambda r, _: f"{float(r['spl']):g}"),
        ("compared", lambda r, _: f"{r['threshold_a']} − {r['threshold_b']}".upper()),
        ("RSSI per run (dBm)", lambda r, _: str(r["statistic"])),
        ("m/n", lambda r, _: f"{r['m']}/{r['n']}"),
        ("medians", lambda r, _: _medians_ab(r)),
        ("shift [95% CI]", lambda r, _: _shift(r)),
        ("p", lambda r, _: fmt_p(r["p"])),
        ("p corr.", lambda r, _: fmt_p(r["p_adj"])),
        ("r [95% CI]", lambda r, _: _r_ci(r)),
        ("decision", lambda r, _: str(r["decision"])),
    ],
}


def _rssi_config(r: pd.Series, multi: bool) -> str:
    text = f"{str(r['network']).upper()}+{str(r['behaviour']).upper()}"
    return (f"{r['scenario']} " if multi else "") + text


def _medians_ab(r: pd.Series) -> str:
    a, b = float(r["median_a"]), float(r["median_b"])
    return "–" if not (math.isfinite(a) and math.isfinite(b)) else f"{a:.1f} vs {b:.1f}"


def _shift(r: pd.Series) -> str:
    text = fmt_num(r["shift"], 1)
    if math.isfinite(float(r["shift_low"])):
        text += f" [{float(r['shift_low']):.1f}, {float(r['shift_high']):.1f}]"
    return text


def _with_ci(r: pd.Series, key: str) -> str:
    text = fmt_num(r[key])
    if math.isfinite(float(r[f"{key}_low"])):
        text += f" [{float(r[f'{key}_low']):.2f}, {float(r[f'{key}_high']):.2f}]"
    return text


def _medians(r: pd.Series) -> str:
    a, b = float(r["median0"]), float(r["median_x"])
    return "–" if not (math.isfinite(a) and math.isfinite(b)) else f"{a:.4g} → {b:.4g}"


#: What a terminal shows of a table (one table per metric, so no metric column); the
#: rest is in CSV, LaTeX and the HTML report.
COMPACT: dict[str, list[Column]] = {
    "comparisons": [
        ("config", _config),
        ("H_A", lambda r, _: str(r["hypothesis"])),
        ("m/n", lambda r, _: f"{r['m']}/{r['n']}"),
        ("median SPL0 → SPLX", lambda r, _: _medians(r)),
        ("p corr.", lambda r, _: _p_adj(r)),
        ("r [95% CI]", lambda r, _: _r_ci(r)),
        ("effect", lambda r, _: str(r["effect"])),
        ("decision", lambda r, _: str(r["decision"])),
    ],
    # The between-behaviour tables: a terminal shows these of their columns.
    **{
        name: [c for c in _COLUMNS[name] if c[0] in shown]
        for name, shown in (
            ("between", ("condition", "behaviours", "medians", "H", "p corr.", "ε²")),
            ("pairwise", ("condition", "A vs B", "medians", "p Holm", "r=Z/√(m+n) [95% CI]")),
        )
    },
    "rssi": [
        ("config", lambda r, multi: _rssi_config(r, multi)),
        ("SPL", lambda r, _: f"{float(r['spl']):g}"),
        ("RSSI per run", lambda r, _: str(r["statistic"])),
        ("medians (dBm)", lambda r, _: _medians_ab(r)),
        ("shift [95% CI]", lambda r, _: _shift(r)),
        ("p corr.", lambda r, _: fmt_p(r["p_adj"])),
        ("decision", lambda r, _: str(r["decision"])),
    ],
}


def display_frame(name: str, frame: pd.DataFrame, compact: bool = False) -> pd.DataFrame:
    """Table ``name`` as rounded strings under readable headers (``compact``: the
    columns a terminal has room for)."""
    columns = COMPACT[name] if compact and name in COMPACT else _COLUMNS[name]
    multi = "scenario" in frame.columns and frame["scenario"].nunique() > 1
    rows = [[fn(row, multi) for _, fn in columns] for _, row in frame.iterrows()]
    return pd.DataFrame(rows, columns=[h for h, _ in columns])


#: Symbols of the displayed tables in LaTeX (applied after escaping; needs booktabs).
_LATEX = (
    ("r=Z/√(m+n)", r"$r=Z/\sqrt{m+n}$"),
    ("r=Z/√n", r"$r=Z/\sqrt{n}$"),
    ("95%", r"95\,\%"),
    ("ε²", r"$\varepsilon^2$"),
    ("†", r"$^\dagger$"),
    ("±", r"$\pm$"),
    ("χ²", r"$\chi^2$"),
    ("≥", r"$\geq$"),
    ("α", r"$\alpha$"),
    ("–", "--"),
    ("<", "$<$"),
    (">", "$>$"),
)


def to_latex(name: str, frame: pd.DataFrame, caption: str = "") -> str:
    """A LaTeX table (booktabs rules, words left-aligned, numbers right-aligned) of the
    displayed table, captioned with its title (and ``caption``); plain ASCII apart from
    the caption, so pdflatex takes it."""
    shown = display_frame(name, frame)
    align = "".join(
        "r" if len(shown) and all(_is_number(str(v)) for v in shown[c]) else "l"
        for c in shown.columns
    )
    text = shown.to_latex(
        index=False,
        escape=True,
        caption=" ".join(filter(None, (TABLE_TITLES[name] + ".", caption))),
        label=f"tab:{name}",
        column_format=align,
        position="htbp",
    )
    for symbol, latex in _LATEX:
        text = text.replace(symbol, latex)
    return text


# ---- loading ------------------------------------------------------------------------------


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
    """The count columns to show: the radio's only when some run had a radio."""
    radio = not table.empty and bool(table[list(RADIO_COUNT_KEYS)].to_numpy().sum() > 0)
    return count_keys(radio)


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
            _config(row, multi),
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


def _is_number(text: str) -> bool:
    """Numbers are right-aligned in the HTML tables, words left-aligned."""
    try:
        float(text.split(" ")[0].lstrip("<"))
    except ValueError:
        return text == "–"
    return True


def _html_table(name: str, frame: pd.DataFrame) -> dict[str, Any]:
    shown = display_frame(name, frame)
    shaded = name in ("comparisons", "between", "pairwise")
    decided = frame["decision"].tolist() if shaded else [""] * len(frame)
    rows = [
        {"cells": [(c, _is_number(c)) for c in cells], "cls": "sig" if flag == st.SUPPORTED else ""}
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
