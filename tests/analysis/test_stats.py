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

from mrcomm.analysis import inference
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
    assert res.direction == "SPL0 lower"


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
    assert res.r_original == pytest.approx(z / math.sqrt(5))  # original: Z / √n, n per group
    assert res.r == pytest.approx(z / math.sqrt(10))  # conventional: Z / √(m+n)
    assert (round(res.z, 4), round(res.r_original, 4), round(res.r, 4)) == (
        -2.6112,
        -1.1677,
        -0.8257,
    )
    assert res.effect == "strong"
    assert res.p == pytest.approx(1 / 252)


def test_effect_size_uses_tie_corrected_z() -> None:
    x, y = [1.0, 2.0, 2.0, 3.0], [2.0, 3.0, 3.0, 4.0, 5.0]
    res = st.mann_whitney(x, y, "less")
    z = (u_by_hand(x, y) - 10.0) / 3.944053188733078
    assert res.z == pytest.approx(z)
    assert res.r_original == pytest.approx(z / 2.0)  # unequal groups: the smaller, n = 4
    assert res.r == pytest.approx(z / 3.0)


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
    assert (same.p, same.z, same.r, same.direction) == (1.0, 0.0, 0.0, "none")
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


# ---- honest presentation: bounded r, reachable designs, corrected p, wording ----------------

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as hs  # noqa: E402

_values = hs.lists(hs.integers(0, 4).map(float), min_size=2, max_size=12)


@settings(max_examples=300, deadline=None)
@given(_values, _values, hs.sampled_from(["less", "greater"]))
def test_lead_effect_size_is_bounded_for_any_data(x: list[float], y: list[float], alt: str) -> None:
    # Few distinct values: heavy ties, all-tied samples and complete separation all occur.
    res = st.mann_whitney(x, y, alt)  # type: ignore[arg-type]
    assert -1.0 <= res.r <= 1.0
    assert res.r_low <= res.r_high or math.isnan(res.r_low)
    assert (res.r_low >= -1.0 and res.r_high <= 1.0) or math.isnan(res.r_low)


def test_all_tied_samples_give_r_zero_and_no_direction() -> None:
    res = st.mann_whitney([2.0] * 6, [2.0] * 6, "less")
    assert (res.r, res.r_original, res.direction, res.p) == (0.0, 0.0, "none", 1.0)
    # Complete separation of two constant samples: the extreme r stays below 1.
    sep = st.mann_whitney([1.0] * 6, [2.0] * 6, "less")
    assert sep.r == pytest.approx(-math.sqrt(11 / 12))
    assert sep.r_original < -1.0  # the original convention exceeds 1, hence not the lead


def test_direction_is_explicit_even_against_the_hypothesis() -> None:
    # SPL0 clearly higher while H_A says lower: strong effect, p near 1, direction shown.
    res = st.mann_whitney([6.0, 7.0, 8.0, 9.0, 10.0], [1.0, 2.0, 3.0, 4.0, 5.0], "less")
    assert res.p == pytest.approx(1.0)
    assert res.effect == "strong" and res.direction == "SPL0 higher" and res.r > 0


@pytest.mark.parametrize(("m", "n", "expected"), [(3, 3, 1 / 20), (5, 5, 1 / 252), (2, 4, 1 / 15)])
def test_minimum_attainable_p(m: int, n: int, expected: float) -> None:
    assert inference.min_attainable_p(m, n) == pytest.approx(expected)
    # The most extreme data reach it exactly.
    res = st.mann_whitney(list(range(m)), list(range(100, 100 + n)), "less")
    assert res.p == pytest.approx(expected) and res.min_p == pytest.approx(expected)


def _two_levels(per_group: int) -> pd.DataFrame:
    rows = []
    for spl in (0.0, 50.0):
        for rep in range(per_group):
            rows.append(
                {
                    "scenario": "s",
                    "network": "ah",
                    "threshold": "none",
                    "behaviour": "nb",
                    "spl": spl,
                    "status": "ok",
                    "successful": True,
                    "execution_phase_time": (100.0 if spl else 10.0) + rep,
                }
            )
    return pd.DataFrame(rows)


def test_a_design_that_cannot_reach_alpha_is_flagged() -> None:
    small = st.comparison_table(_two_levels(3), ["execution_phase_time"], correction="none")
    row = small.iloc[0]
    # Perfect separation, yet p = 0.05 = the minimum: not significant, and flagged.
    assert row["p"] == pytest.approx(0.05) and not row["reachable"]
    assert row["decision"] == st.NOT_REJECTED
    (warning,) = st.unreachable(small)
    assert "3 vs 3 runs cannot be significant" in warning and "0.05" in warning
    big = st.comparison_table(_two_levels(5), ["execution_phase_time"], correction="none")
    assert bool(big.iloc[0]["reachable"]) and big.iloc[0]["decision"] == st.SUPPORTED
    assert st.unreachable(big) == []


def test_holm_and_bh_against_a_hand_computation() -> None:
    p = [0.01, 0.04, 0.03, 0.005, math.nan]
    # Holm: sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1 = 0.02, 0.03, 0.06, 0.04,
    # made non-decreasing: 0.02, 0.03, 0.06, 0.06.
    holm = inference.adjust_p(p, "holm")
    assert holm[:4] == pytest.approx([0.03, 0.06, 0.06, 0.02]) and math.isnan(holm[4])
    # BH: times 4/1, 4/2, 4/3, 4/4 = 0.02, 0.02, 0.04, 0.04 (already monotone).
    assert inference.adjust_p(p, "bh")[:4] == pytest.approx([0.02, 0.04, 0.04, 0.02])
    assert inference.adjust_p([0.6, 0.9], "holm") == pytest.approx([1.0, 1.0])  # capped at 1
    assert inference.adjust_p(p, "none")[:4] == pytest.approx(p[:4])
    with pytest.raises(InputError, match="unknown correction"):
        inference.check_correction("bonferoni")


def test_the_table_decides_on_the_corrected_p_with_not_rejected_wording() -> None:
    runs = _two_levels(5)
    runs["total_distance"] = [1.0, 2.0, 3.0, 4.0, 5.0, 3.5, 4.5, 5.5, 6.5, 7.5]
    table = st.comparison_table(runs, ["execution_phase_time", "total_distance"])
    assert list(table["metric"]) == ["execution_phase_time", "total_distance"]
    assert table["p_adj"].tolist() == pytest.approx(list(inference.adjust_p(table["p"].tolist())))
    assert set(table["decision"]) <= {st.SUPPORTED, st.NOT_REJECTED}
    assert table["decision"].tolist() == [
        st.SUPPORTED if p < st.ALPHA else st.NOT_REJECTED for p in table["p_adj"]
    ]
    assert "accepted" not in " ".join(table.columns)


def test_bootstrap_intervals_are_seeded_and_cover_the_estimate() -> None:
    rng = np.random.default_rng(3)
    x = rng.normal(10.0, 2.0, 20)
    low, high = inference.bootstrap_ci((x,), np.mean)
    assert low < float(np.mean(x)) < high
    assert (low, high) == inference.bootstrap_ci((x,), np.mean)  # same data, same interval
    assert math.isnan(inference.bootstrap_ci((x[:1],), np.mean)[0])
    desc = st.describe_table(_two_levels(5), ["execution_phase_time"])
    assert (desc["mean_low"] <= desc["mean"]).all() and (desc["mean"] <= desc["mean_high"]).all()
