"""The statistics of a study against values computed by hand or independently of scipy:
U of the SPL0 sample, exact p for n = 5 (with and without ties, by enumerating every
split), the tie-corrected σ_U, the normal approximation, both effect-size conventions,
Shapiro–Wilk (closed form for n = 3), chi-squared and Fisher's exact test."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
import pytest

from mrcomm.analysis import stats as st
from mrcomm.errors import InputError


def u_by_hand(x: list[float], y: list[float]) -> float:
    """U of x: pairs with x > y, ties counting one half."""
    return sum(1.0 if a > b else 0.5 if a == b else 0.0 for a in x for b in y)


def exact_p_by_enumeration(x: list[float], y: list[float], alternative: str) -> float:
    """P(U <= u_obs) ('less') or P(U >= u_obs) over every split of the pooled sample."""
    pooled = x + y
    observed = u_by_hand(x, y)
    hits = total = 0
    for idx in itertools.combinations(range(len(pooled)), len(x)):
        chosen = set(idx)
        a = [pooled[i] for i in idx]
        b = [pooled[i] for i in range(len(pooled)) if i not in chosen]
        u = u_by_hand(a, b)
        hits += (u <= observed + 1e-9) if alternative == "less" else (u >= observed - 1e-9)
        total += 1
    return hits / total


def normal_cdf(z: float) -> float:
    return 0.5 * math.erfc(-z / math.sqrt(2.0))


def test_u_is_the_statistic_of_the_spl0_sample() -> None:
    x, y = [3.0, 1.0, 4.0, 1.5, 5.0], [9.0, 2.0, 6.0, 5.5, 3.5]
    res = st.mann_whitney(x, y, "less")
    # Pairs with SPL0 > SPLX: 3>2, 4>2, 4>3.5, 5>2, 5>3.5.
    assert res.u == u_by_hand(x, y) == 5.0
    # Swapping the samples gives the other U (U1 + U2 = mn): the reported one is SPL0's.
    assert st.mann_whitney(y, x, "less").u == 25 - 5.0


def test_exact_p_n5_without_ties_matches_enumeration() -> None:
    x, y = [1.1, 2.3, 3.0, 4.8, 7.0], [3.5, 5.0, 6.2, 8.1, 9.9]
    res = st.mann_whitney(x, y, "less")
    assert res.method == "exact"
    assert res.u == 4.0  # 4.8 > 3.5; 7.0 > 3.5, 5.0, 6.2
    assert res.p == pytest.approx(exact_p_by_enumeration(x, y, "less"), abs=1e-12)
    # Splits of 10 into 5 + 5 with U = 0, 1, 2, 3, 4: 1 + 1 + 2 + 3 + 5 of 252.
    assert res.p == pytest.approx(12 / 252)
    assert res.accepted == "HA"


def test_exact_p_n5_with_ties_enumerates_every_split() -> None:
    x, y = [1.0, 2.0, 2.0, 3.0, 5.0], [2.0, 3.0, 4.0, 5.0, 6.0]
    res = st.mann_whitney(x, y, "less")
    assert res.method.startswith("exact permutation")
    assert res.u == u_by_hand(x, y) == 6.0
    assert res.p == pytest.approx(exact_p_by_enumeration(x, y, "less"), abs=1e-12)
    greater = st.mann_whitney(x, y, "greater")
    assert greater.p == pytest.approx(exact_p_by_enumeration(x, y, "greater"), abs=1e-12)


def test_tie_corrected_sigma_by_hand() -> None:
    # Values 2 (three times) and 3 (three times) tie: Σ(t³−t) = 24 + 24 = 48, N = 9.
    x, y = [1.0, 2.0, 2.0, 3.0], [2.0, 3.0, 3.0, 4.0, 5.0]
    expected = math.sqrt(4 * 5 / 12 * ((9 + 1) - 48 / (9 * 8)))
    assert st.sigma_u(x, y) == pytest.approx(expected)
    assert expected == pytest.approx(3.94405, abs=1e-5)
    # Without ties: the SPEC's √(mn(m+n+1)/12).
    assert st.sigma_u([1, 2, 3], [4, 5, 6, 7]) == pytest.approx(math.sqrt(3 * 4 * 8 / 12))


def test_effect_size_conventions_by_hand() -> None:
    x, y = [1.0, 2.0, 3.0, 4.0, 5.0], [6.0, 7.0, 8.0, 9.0, 10.0]
    res = st.mann_whitney(x, y, "less")
    sigma = math.sqrt(5 * 5 * 11 / 12)  # 4.7871
    z = (0.0 - 12.5) / sigma  # -2.6112
    assert res.z == pytest.approx(z)
    assert res.r == pytest.approx(z / math.sqrt(5))  # original: Z / √n, n per group
    assert res.r_conv == pytest.approx(z / math.sqrt(10))  # conventional: Z / √(m+n)
    assert (round(res.z, 4), round(res.r, 4), round(res.r_conv, 4)) == (-2.6112, -1.1677, -0.8257)
    assert res.effect == "strong"
    assert res.p == pytest.approx(1 / 252)


def test_effect_size_uses_tie_corrected_z() -> None:
    x, y = [1.0, 2.0, 2.0, 3.0], [2.0, 3.0, 3.0, 4.0, 5.0]
    res = st.mann_whitney(x, y, "less")
    z = (u_by_hand(x, y) - 10.0) / 3.944053188733078
    assert res.z == pytest.approx(z)
    assert res.r == pytest.approx(z / 2.0)  # unequal groups: the smaller, n = 4
    assert res.r_conv == pytest.approx(z / 3.0)


def test_large_samples_with_ties_use_the_normal_approximation() -> None:
    rng = np.random.default_rng(5)
    x = np.round(rng.normal(10, 2, 30))
    y = np.round(rng.normal(11.5, 2, 30))
    res = st.mann_whitney(x, y, "less")
    assert res.method.startswith("normal")
    u = u_by_hand(list(x), list(y))
    sigma = st.sigma_u(x, y)
    # scipy's continuity correction moves U half a unit towards the mean.
    assert res.p == pytest.approx(normal_cdf((u - 450 + 0.5) / sigma), rel=1e-9)
    assert res.z == pytest.approx((u - 450) / sigma)


@pytest.mark.parametrize(
    ("r", "label"),
    [
        (0.05, "negligible"),
        (-0.1, "weak"),
        (0.29, "weak"),
        (0.3, "medium"),
        (-0.5, "medium"),
        (0.51, "strong"),
        (-1.2, "strong"),
        (math.nan, "n/a"),
    ],
)
def test_cohen_labels(r: float, label: str) -> None:
    assert st.effect_label(r) == label


def test_degenerate_and_tiny_samples() -> None:
    same = st.mann_whitney([0, 0, 0], [0, 0, 0, 0], "greater")
    assert (same.p, same.z, same.r, same.accepted) == (1.0, 0.0, 0.0, "H0")
    assert same.u == 6.0
    tiny = st.mann_whitney([1.0], [2.0, 3.0], "less")
    assert math.isnan(tiny.p) and tiny.method == "too few"
    nan_dropped = st.mann_whitney([1.0, np.nan, 2.0, 3.0], [4.0, 5.0, 6.0], "less")
    assert nan_dropped.m == 3 and nan_dropped.p == pytest.approx(1 / 20)


def test_shapiro_wilk_n3_closed_form() -> None:
    # n = 3: a = (−1/√2, 0, 1/√2); p = 6/π (asin √W − asin √(3/4)).
    x = [1.0, 2.0, 4.0]
    ss = sum((v - 7 / 3) ** 2 for v in x)
    w = (3.0 / math.sqrt(2)) ** 2 / ss
    p = 6 / math.pi * (math.asin(math.sqrt(w)) - math.asin(math.sqrt(0.75)))
    got_w, got_p = st.shapiro_wilk(x)
    assert got_w == pytest.approx(w, abs=1e-4)
    assert got_p == pytest.approx(p, abs=1e-3)
    assert all(math.isnan(v) for v in st.shapiro_wilk([2.0, 2.0, 2.0]))
    assert all(math.isnan(v) for v in st.shapiro_wilk([1.0, 2.0]))


def test_chi_squared_and_fisher_by_hand() -> None:
    table = np.array([[8, 2], [3, 7]])
    # Yates: expected 5.5/4.5 in each column, (|O−E| − 0.5)² = 4.
    chi2 = 4 / 5.5 + 4 / 4.5 + 4 / 5.5 + 4 / 4.5
    out = st.chi_squared(table)
    assert out["chi2"] == pytest.approx(chi2)
    assert out["p"] == pytest.approx(math.erfc(math.sqrt(chi2 / 2)))  # χ², 1 dof

    # Fisher two-sided: sum of hypergeometric P(a) <= P(observed), a = cell (0, 0).
    def prob(a: int) -> float:
        return math.comb(10, a) * math.comb(10, 11 - a) / math.comb(20, 11)

    observed = prob(8)
    fisher = sum(prob(a) for a in range(1, 11) if prob(a) <= observed * (1 + 1e-7))
    assert out["fisher_p"] == pytest.approx(fisher)
    assert out["dof"] == 1 and out["min_expected"] == pytest.approx(4.5)
    assert "Fisher" in str(out["note"])
    assert st.chi_squared(np.array([[5, 0], [5, 0]]))["note"] == "all successful"
    assert math.isnan(float(st.chi_squared(np.array([[0, 5], [0, 5]]))["p"]))


def _runs(rows: list[tuple[str, float, str, list[float]]], metric: str) -> pd.DataFrame:
    out = []
    for behaviour, spl, status, values in rows:
        for i, v in enumerate(values):
            out.append(
                {
                    "run_id": f"{behaviour}{spl:g}-r{i}",
                    "scenario": "S1",
                    "network": "ah",
                    "threshold": "slt",
                    "behaviour": behaviour,
                    "spl": spl,
                    "repetition": i,
                    "status": status,
                    "successful": v < 5,
                    metric: v,
                }
            )
    return pd.DataFrame(out)


def test_comparison_table_groups_directions_and_status() -> None:
    runs = _runs(
        [
            ("nb", 0.0, "ok", [1, 2, 3, 4, 5]),
            ("nb", 50.0, "ok", [6, 7, 8, 9, 10]),
            ("nb", 50.0, "error", [-100]),  # ignored: the run did not finish
            ("lf", 25.0, "ok", [1, 2, 3]),  # no SPL0 in this group: nothing to compare
        ],
        "near_collisions",
    )
    table = st.comparison_table(runs, ["near_collisions"])
    assert len(table) == 1
    row = table.iloc[0]
    assert (row["behaviour"], row["spl_x"], row["m"], row["n"]) == ("nb", 50.0, 5, 5)
    assert row["alternative"] == "greater" and row["hypothesis"] == "SPL0 > SPL50"
    assert row["u"] == 0.0 and row["p"] == pytest.approx(1.0)  # SPL0 is *less*: H0 kept
    assert row["mean0"] == 3.0 and row["sd0"] == pytest.approx(np.std([1, 2, 3, 4, 5], ddof=1))


def test_lf_metric_of_nb_runs_is_skipped() -> None:
    runs = _runs([("nb", 0.0, "ok", [1, 2, 3]), ("nb", 50.0, "ok", [4, 5, 6])], "delay_time")
    runs["leader_movement_time"] = np.nan
    table = st.comparison_table(runs, ["delay_time", "leader_movement_time"])
    assert list(table["metric"]) == ["delay_time"]


def test_success_tables() -> None:
    runs = _runs([("nb", 0.0, "ok", [1, 2, 3, 9]), ("nb", 50.0, "ok", [9, 9, 9, 1])], "x")
    counts = st.success_counts(runs)
    assert counts[["spl", "successful", "failed"]].values.tolist() == [[0.0, 3, 1], [50.0, 1, 3]]
    tests = st.success_tests(runs)
    assert list(tests["comparison"]) == ["all SPL levels", "SPL0 vs SPL50"]
    expected = st.chi_squared(np.array([[3, 1], [1, 3]]))
    assert tests.iloc[1]["chi2"] == pytest.approx(expected["chi2"])


def test_unknown_metric_is_an_input_error() -> None:
    with pytest.raises(InputError, match="did you mean 'delay_time'"):
        st.resolve_metrics(["delay_tme"])
