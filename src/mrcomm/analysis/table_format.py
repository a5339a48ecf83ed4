"""The human formatting of the statistics tables, for the two places people read them:
the HTML report and ``mrcomm analyze`` (terminal tables and LaTeX). Titles, p-values,
effect sizes with their intervals, mean ± SD and median (IQR), and the columns shown."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import pandas as pd

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


def config_label(r: pd.Series, multi: bool) -> str:
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
_CFG: Column = ("configuration", config_label)
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
        ("config", config_label),
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
        "r" if len(shown) and all(is_number(str(v)) for v in shown[c]) else "l"
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


def is_number(text: str) -> bool:
    """Numbers are right-aligned in the HTML tables, words left-aligned."""
    try:
        float(text.split(" ")[0].lstrip("<"))
    except ValueError:
        return text == "–"
    return True
