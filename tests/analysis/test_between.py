"""Statistics between behaviours: Kruskal–Wallis and pairwise Mann–Whitney agree with
scipy on the same samples, Holm is applied within each condition's pairs, conditions
(threshold, SPL, setting) are kept apart, and a threshold-blind baseline joins every
threshold."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

from mrcomm.analysis.between import kruskal_table, pairwise_table
from mrcomm.analysis.settings import with_settings

METRIC = "execution_phase_time"


def _runs(samples: dict[tuple[str, str, float, str], list[float]]) -> pd.DataFrame:
    rows = []
    for (behaviour, threshold, spl, setting), values in samples.items():
        for i, v in enumerate(values):
            rows.append({
                "run_id": f"{behaviour}-{threshold}-{spl}-{setting}-{i}", "scenario": "S1",
                "network": "ah", "threshold": threshold, "spl": spl, "setting": setting,
                "behaviour": behaviour, "status": "ok", METRIC: v,
            })  # fmt: skip
    return pd.DataFrame(rows)


RNG = np.random.default_rng(5)
A = list(RNG.normal(300, 10, 10))
B = list(RNG.normal(330, 10, 10))
C = list(RNG.normal(302, 10, 10))


def test_kruskal_wallis_and_pairs_agree_with_scipy() -> None:
    runs = _runs({("lf", "slt", 0, ""): A, ("lf-wait", "slt", 0, ""): B, ("rps", "slt", 0, ""): C})
    omnibus = kruskal_table(runs, [METRIC])
    assert len(omnibus) == 1
    row = omnibus.iloc[0]
    expected = sps.kruskal(A, B, C)
    assert row["h"] == pytest.approx(expected.statistic)
    assert row["p"] == pytest.approx(expected.pvalue)
    assert row["df"] == 2 and row["n"] == 30
    assert row["epsilon2"] == pytest.approx(expected.statistic / 29)
    pairs = pairwise_table(runs, [METRIC])
    assert list(zip(pairs["behaviour_a"], pairs["behaviour_b"], strict=True)) == [
        ("lf", "lf-wait"), ("lf", "rps"), ("lf-wait", "rps"),
    ]  # fmt: skip
    raw = [
        sps.mannwhitneyu(x, y, alternative="two-sided").pvalue for x, y in ((A, B), (A, C), (B, C))
    ]
    assert pairs["p"].tolist() == pytest.approx(raw)
    # Holm over the three pairs: sorted p times 3, 2, 1, made non-decreasing.
    order = np.argsort(raw)
    holm = np.maximum.accumulate(np.asarray(raw)[order] * [3, 2, 1]).clip(max=1)
    assert pairs["p_adj"].to_numpy()[order] == pytest.approx(holm)
    far = pairs[(pairs["behaviour_a"] == "lf") & (pairs["behaviour_b"] == "lf-wait")].iloc[0]
    assert far["r"] < -0.6 and far["direction"] == "lf lower" and far["r_high"] < 0
    near = pairs[(pairs["behaviour_a"] == "lf") & (pairs["behaviour_b"] == "rps")].iloc[0]
    assert near["decision"] == "H0 not rejected"


def test_identical_behaviours_give_no_difference_and_one_behaviour_no_table() -> None:
    same = _runs({("lf", "slt", 0, ""): [1.0] * 5, ("nb", "slt", 0, ""): [1.0] * 5})
    row = kruskal_table(same, [METRIC]).iloc[0]
    assert (row["h"], row["p"]) == (0.0, 1.0)
    pair = pairwise_table(same, [METRIC]).iloc[0]
    assert pair["p"] == 1.0 and pair["r"] == 0.0
    alone = _runs({("lf", "slt", 0, ""): A})
    assert kruskal_table(alone, [METRIC]).empty and pairwise_table(alone, [METRIC]).empty


def test_conditions_are_kept_apart_and_nb_joins_every_threshold() -> None:
    runs = _runs({
        ("nb", "slt", 0, ""): C,
        ("lf", "slt", 0, ""): A, ("lf", "ssd", 0, ""): B,
        ("lf-wait", "slt", 0, ""): B, ("lf-wait", "ssd", 0, ""): A,
        ("lf", "slt", 0, "network.relay=true"): A, ("lf-wait", "slt", 0, "network.relay=true"): C,
    })  # fmt: skip
    table = kruskal_table(runs, [METRIC])
    got = {(r.threshold, r.setting): r.behaviours for r in table.itertuples()}
    assert got == {
        ("slt", ""): "lf, lf-wait, nb",
        ("ssd", ""): "lf, lf-wait, nb",  # NB ignores the threshold: its SLT runs join
        ("slt", "network.relay=true"): "lf, lf-wait",
    }


def test_the_tables_are_deterministic() -> None:
    runs = _runs({("lf", "slt", 0, ""): A, ("lf-wait", "slt", 0, ""): B})
    pd.testing.assert_frame_equal(pairwise_table(runs, [METRIC]), pairwise_table(runs, [METRIC]))


def test_settings_come_from_the_configurations() -> None:
    runs = pd.DataFrame({"run_id": ["a", "b", "c"], "config_id": ["x", "y", "z"],
                         "behaviour": ["lf", "lf", "nb"]})  # fmt: skip
    configs = pd.DataFrame({
        "config_id": ["x", "y", "z"],
        "options": [
            '{"params": {}}',
            '{"params": {"network": {"relay": true}, "behaviour": {"utility": "greedy"}}}',
            '{"params": {"network": {"relay": true}}}',
        ],
    })  # fmt: skip
    out = with_settings(runs, configs)
    assert out["behaviour"].tolist() == ["lf", 'lf[utility="greedy"]', "nb"]
    assert out["setting"].tolist() == ["", "network.relay=true", "network.relay=true"]


def test_the_report_and_analyze_show_the_between_behaviour_tests(
    built: Any, study_db: Path
) -> None:
    from .conftest import mrcomm

    html = built.html.read_text()
    assert "Between behaviours" in html
    between = pd.read_csv(built.out_dir / "tables" / "between.csv")
    assert set(between["behaviours"]) == {"lf, nb"}
    assert (built.out_dir / "tables" / "pairwise.csv").is_file()
    done = mrcomm("analyze", "--db", str(study_db), "--metric", METRIC, "--table", "pairwise")
    assert done.returncode == 0, done.stderr
    assert "pairwise Mann-Whitney" in done.stdout and "lf vs nb" in done.stdout
