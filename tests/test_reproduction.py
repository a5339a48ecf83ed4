"""The reproduction of the original study (docs/REPRODUCTION.md, ``make reproduce``).

* The original's statistic is computed as the thesis did: from a printed U, our
  one-sided p (normal approximation, continuity correction, no tie correction) and
  r = Z/√n give the printed p and r on the rows the thesis did not copy.
* The verdict rules say what the report says they say.
* The report's machinery, run small (3 runs per configuration into copies of the page),
  rewrites both generated blocks, with 105 comparisons per study and the figures, and
  leaves the hand-written text alone.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pandas as pd
import pytest

from mrcomm.analysis.reproduction import (
    DIRECTION,
    NOT_REPRODUCED,
    REPRODUCED,
    compare,
    load_original,
    mann_whitney_verdict,
    r_tolerance,
    thesis_p,
    thesis_r,
)
from mrcomm.analysis.stats import all_metrics
from tests.conftest import ROOT
from tests.test_docs_tables import _block, docs_tables


def test_the_original_file_holds_every_table_of_its_simulation_chapters() -> None:
    original = load_original()
    tables = {t["table"]: len(t["rows"]) for t in original["mann_whitney"]}
    assert tables == {"4.9": 9, "5.4": 9, "5.5": 9, "5.6": 18, "5.7": 12, "5.8": 12,
                      "5.9": 9, "5.10": 12}  # fmt: skip
    metrics = all_metrics()
    for table in original["mann_whitney"]:
        for row in table["rows"]:
            assert row["metric"] in metrics, row
            assert row["decision"] in ("H_A", "H_0")
    assert original["success"][0]["successful"] == {0: 30, 25: 6, 50: 0, 75: 0}


def test_the_thesis_statistic_gives_its_printed_p_and_r() -> None:
    """Tables 4.9 (lines 1438-1452) and 5.10 (lines 1842-1859), n = 30 per group."""
    original = load_original()
    checked = 0
    for table in original["mann_whitney"]:
        if table["table"] not in ("4.9", "5.10"):
            continue
        for row in table["rows"]:
            p = thesis_p(row["U"], 30, 30, table["alternative"])
            assert abs(p - row["p"]) <= 0.011, row
            assert abs(thesis_r(row["U"], 30, 30) - row["r"]) <= 0.011, row
            checked += 1
    assert checked == 21
    # Table 5.6 tests the other direction ("greater"): U 894 of 900, r 1.19 printed.
    assert thesis_p(894, 30, 30, "greater") < 1e-9
    assert math.isclose(thesis_r(894, 30, 30), 1.195, abs_tol=0.01)


def test_the_verdict_rules() -> None:
    band = r_tolerance(30)
    assert math.isclose(band, 0.506, abs_tol=0.001)
    theirs = {"p": 0.001, "r": -0.9}
    assert mann_whitney_verdict({"p": 0.01, "r": -0.6}, theirs, 30) == REPRODUCED
    assert mann_whitney_verdict({"p": 0.01, "r": -0.3}, theirs, 30) == DIRECTION  # too small
    assert mann_whitney_verdict({"p": 0.2, "r": -0.2}, theirs, 30) == DIRECTION  # not significant
    assert mann_whitney_verdict({"p": 0.9, "r": 0.3}, theirs, 30) == NOT_REPRODUCED
    # Two null findings of opposite sign within the band are the same finding.
    assert mann_whitney_verdict({"p": 0.6, "r": 0.1}, {"p": 0.3, "r": -0.1}, 30) == REPRODUCED


def _runs(successful_at_25: int) -> pd.DataFrame:
    """A WLAN NB study whose SPL 25 has ``successful_at_25`` of 30 successful runs."""
    rows = []
    for spl, ok in ((0, 30), (25, successful_at_25), (50, 0), (75, 0)):
        for i in range(30):
            rows.append({"network": "wlan", "threshold": "slt", "behaviour": "nb", "spl": spl,
                         "successful": i < ok, "n_failed_tasks": 0 if i < ok else 1,
                         "status": "ok"})  # fmt: skip
    return pd.DataFrame(rows)


def test_success_counts_are_judged_by_fishers_test() -> None:
    original = load_original()
    only = {**original, "claims": [], "mann_whitney": []}
    close = compare(_runs(4), only)
    assert close.loc[1, "ours"] == "4/30" and close.loc[1, "verdict"] == REPRODUCED
    far = compare(_runs(25), only)
    assert far.loc[1, "verdict"] == DIRECTION  # fewer than at SPL 0, but far more than 6


@pytest.mark.slow
def test_a_small_reproduction_rewrites_the_report(tmp_path: Path) -> None:
    page = tmp_path / "docs" / "REPRODUCTION.md"
    (tmp_path / "docs" / "figures").mkdir(parents=True)
    original = (ROOT / "docs" / "REPRODUCTION.md").read_text()
    stale = original
    for name in ("reproduction-summary", "reproduction-table"):
        stale = stale.replace(_block(original, name), f"stale {name}")
    page.write_text(stale)
    docs_tables._REPRODUCTION.clear()
    docs_tables.main(["--only", "reproduction-summary", "--only", "reproduction-table",
                      "--reps", "3", "--jobs", "2", "--docs", str(tmp_path),
                      "--results", str(tmp_path / "results")])  # fmt: skip
    written = page.read_text()
    summary = _block(written, "reproduction-summary")
    assert "144 runs (3 repetitions)" in summary and "stale" not in written
    assert summary.count("| 105 |") == 2  # both studies, every comparison
    table = _block(written, "reproduction-table")
    numbered = [line for line in table.splitlines() if re.match(r"\| \d+ \|", line)]
    assert len(numbered) == 105
    for stem in ("reproduction_effects", "reproduction_success"):
        assert (tmp_path / "docs" / "figures" / f"{stem}.png").stat().st_size > 10_000
    # The hand-written text is as it was.
    rest = written
    for name in ("reproduction-summary", "reproduction-table"):
        rest = rest.replace(_block(written, name), f"stale {name}")
    assert rest == stale


@pytest.mark.slow
def test_followers_driving_to_the_leaders_pose_keep_the_hold_time_flat_under_loss(
    s1_resources: object,
) -> None:
    """The original robots' profile's second mechanism (Algorithm 5: the follower goes to
    the leader's last pose): with it the leader's hold time on WLAN · SLT does not grow
    from SPL 0 to SPL 75 and LF's near collisions fall (Tables 5.5 and 5.6); with
    MRComm's followers, which stop 1.2 m short, the hold time doubles (6 seeds)."""
    from mrcomm.run.config import make_config
    from mrcomm.sim.mission import run_mission
    from tests.golden.golden import SCENARIO

    def means(follow: dict[str, float], spl: float) -> tuple[float, float]:
        params = {"behaviour": {"judge_poses": "on_receipt", **follow}}
        runs = [
            run_mission(make_config(None, scenario=SCENARIO, network="wlan", threshold="slt",
                                    behaviour="lf", spl=spl, seed=seed, params=params),
                        s1_resources).mission  # type: ignore[arg-type]
            for seed in range(1, 7)
        ]  # fmt: skip
        hold = sum(r["leader_disconnect_time"] for r in runs) / len(runs)
        collisions = sum(r["near_collisions"] for r in runs) / len(runs)
        return hold, collisions

    to_the_pose = {"follow_distance": 0.65}
    hold_0, collisions_0 = means(to_the_pose, 0.0)
    hold_75, collisions_75 = means(to_the_pose, 75.0)
    assert hold_75 < 1.3 * hold_0
    assert collisions_75 < collisions_0
    short_0, _ = means({}, 0.0)
    short_75, _ = means({}, 75.0)
    assert short_75 > 1.6 * short_0


def test_the_hold_diagnostic_finds_slt_holds_only_beyond_its_warning_distance(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """scripts/reproduction_holds.py (quoted in "SSD against SLT"): with SLT a leader
    holds only for followers beyond SLT's 4 m warning distance."""
    from tests.scripts import load_script

    monkeypatch.chdir(ROOT)
    script = load_script(ROOT / "scripts" / "reproduction_holds.py", "reproduction_holds")
    script.holds("slt", 0.0, 1)
    out = capsys.readouterr().out
    held = float(re.search(r"holds ([\d.]+) s", out).group(1))  # type: ignore[union-attr]
    bins = [float(b) for b in re.findall(r"'(\d+\.\d)': ", out)]
    assert held > 0 and bins and min(bins) >= 4.0


def test_the_separation_as_heard_is_the_true_one_when_every_pose_arrives(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """scripts/reproduction_separation.py (quoted in "What is left"): with every pose
    arriving (5 a second), the separation a robot heard is within a pose's travel of the
    true one; a robot out of AH's range hears its mates' old poses, further off."""
    from tests.scripts import load_script

    monkeypatch.chdir(ROOT)
    load_script(ROOT / "scripts" / "reproduction_holds.py", "reproduction_holds")
    script = load_script(ROOT / "scripts" / "reproduction_separation.py", "reproduction_separation")
    true_max, heard_max = script.separations("lf", "wlan", 0.0, 1)
    assert 3.0 < true_max < 8.0 and abs(heard_max - true_max) < 0.3
    true_max, heard_max = script.separations("nb", "ah", 0.0, 1)
    assert true_max > 20.0 and heard_max > true_max + 1.0
