"""Every statistics table of a study in one object: the comparisons, normality,
descriptive statistics and success tables of :mod:`mrcomm.analysis.stats`, the SSD vs
ESD comparison of :mod:`mrcomm.analysis.rssi_compare`, and the between-behaviour tests
of :mod:`mrcomm.analysis.between` (``mrcomm analyze``, the report's tables/)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import pandas as pd

from mrcomm.analysis.between import kruskal_table, pairwise_table
from mrcomm.analysis.inference import Correction
from mrcomm.analysis.rssi_compare import rssi_comparisons
from mrcomm.analysis.stats import (
    ALPHA,
    comparison_table,
    describe_table,
    normality_table,
    success_counts,
    success_tests,
)

#: Table names of a study, in the order they are printed and written.
TABLE_NAMES = (
    "comparisons",
    "normality",
    "descriptive",
    "success_counts",
    "success_tests",
    "rssi",
    "between",
    "pairwise",
)


@dataclass(frozen=True)
class StudyTables:
    """Every statistics table of a study (the CSVs of the report)."""

    comparisons: pd.DataFrame
    normality: pd.DataFrame
    descriptive: pd.DataFrame
    success_counts: pd.DataFrame
    success_tests: pd.DataFrame
    #: SSD vs ESD: the RSSI of configurations differing only in their threshold.
    rssi: pd.DataFrame
    #: Kruskal–Wallis across behaviours per condition (empty with one behaviour).
    between: pd.DataFrame
    #: Pairwise Mann–Whitney between behaviours, Holm within each condition.
    pairwise: pd.DataFrame

    def get(self, name: str) -> pd.DataFrame:
        frame: pd.DataFrame = getattr(self, name)
        return frame


def study_tables(
    runs: pd.DataFrame,
    metrics: Sequence[str] | None = None,
    alpha: float = ALPHA,
    correction: Correction = "holm",
    *,
    rssi: pd.DataFrame | None = None,
    trajectories: pd.DataFrame | None = None,
) -> StudyTables:
    """Every table; the RSSI comparison needs the runs' ``rssi`` and ``trajectories``
    (empty without them)."""
    empty = pd.DataFrame(columns=["run_id", "t", "src", "dst", "rssi"])
    return StudyTables(
        comparisons=comparison_table(runs, metrics, alpha, correction),
        normality=normality_table(runs, metrics, alpha),
        descriptive=describe_table(runs, metrics),
        success_counts=success_counts(runs),
        success_tests=success_tests(runs),
        rssi=rssi_comparisons(
            runs,
            rssi if rssi is not None else empty,
            trajectories if trajectories is not None else pd.DataFrame(),
            alpha,
            correction,
        ),
        between=kruskal_table(runs, metrics, alpha, correction),
        pairwise=pairwise_table(runs, metrics, alpha),
    )
