"""The study report from a real swept database: every file written, the HTML
self-contained (figures embedded as PNG, no script, nothing fetched), tables equal to
the statistics, nothing written on failure; run choice for timelines and RSSI."""

from __future__ import annotations

import base64
import json
import re
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import mrcomm
from mrcomm.analysis import figures_report as fr
from mrcomm.analysis import report as rp
from mrcomm.analysis import stats as st
from mrcomm.analysis import table_format as tf
from mrcomm.analysis.study import TABLE_NAMES
from mrcomm.errors import InputError

IMG = re.compile(r'<img src="([^"]+)" alt="([^"]*)">')


def test_report_writes_html_figures_and_tables(built: rp.Report, study: Any) -> None:
    assert built.html.is_file()
    for fid in built.figures:
        png = (built.out_dir / "figures" / f"{fid}.png").read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        assert b"<svg" in (built.out_dir / "figures" / f"{fid}.svg").read_bytes()[:500]
    expected = {"success", "time_breakdown", "separation", "failed_per_robot"}
    assert expected <= set(built.figures)
    assert {f"metric_{m}" for m in st.CORE_METRICS} <= set(built.figures)
    assert {f"qq_{m}" for m in st.CORE_METRICS} <= set(built.figures)
    # One timeline per behaviour by default.
    assert len([f for f in built.figures if f.startswith("timeline_")]) == 2
    assert sorted(p.stem for p in (built.out_dir / "tables").glob("*.csv")) == sorted(TABLE_NAMES)


def test_html_is_self_contained(built: rp.Report, study_db: Path) -> None:
    html = built.html.read_text()
    images = IMG.findall(html)
    assert len(images) == len(built.figures)
    for src, _ in images:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
    assert "<script" not in html and "<link" not in html
    assert not re.search(r'(src|href)="(https?:)?//', html)  # nothing fetched
    assert f"mrcomm {mrcomm.__version__}" in html and "Generated 20" in html
    assert str(study_db) in html and "AH_LF_SPL50_SLT" in html
    assert "Mann" in html and "Shapiro" in html and "Chi-squared" in html


def test_csv_tables_are_the_statistics(built: rp.Report, study: Any) -> None:
    csv = pd.read_csv(built.out_dir / "tables" / "comparisons.csv")
    direct = st.comparison_table(study.runs, fr.metrics_with_data(study.runs))
    assert len(csv) == len(direct) > 0
    assert list(csv["metric"]) == list(direct["metric"])
    pd.testing.assert_series_equal(csv["p"], direct["p"], check_names=False)
    counts = pd.read_csv(built.out_dir / "tables" / "success_counts.csv")
    assert counts["runs"].sum() == len(study.runs)


def test_nothing_is_written_when_a_figure_fails(
    study: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken(*args: Any, **kwargs: Any) -> Any:
        raise RuntimeError("figure failed")

    # The last figure fails: every other one has been drawn, nothing may be on disk.
    monkeypatch.setattr(fr.figures_time, "rssi_figure", broken)
    monkeypatch.setattr(fr, "pick_rssi_runs", lambda runs, rssi: ["x"])
    out = tmp_path / "out"
    with pytest.raises(RuntimeError):
        rp.build_report(study, out, metrics=["delay_time"], svg=False)
    assert not out.exists()


def test_a_report_over_an_older_one_keeps_only_its_own_figures(study: Any, tmp_path: Path) -> None:
    out = tmp_path / "out"
    first = rp.build_report(study, out, metrics=["delay_time", "idle_time"], svg=True)
    assert (out / "figures" / "metric_idle_time.svg").is_file()
    second = rp.build_report(study, out, metrics=["delay_time"], svg=False)
    on_disk = sorted(p.name for p in (out / "figures").iterdir())
    assert on_disk == sorted(f"{fid}.png" for fid in second.figures)
    assert "metric_idle_time" in first.figures and "metric_idle_time" not in second.figures


def test_timeline_runs_are_checked(study: Any) -> None:
    run_id = str(study.runs["run_id"].iloc[0])
    assert fr.pick_timeline_runs(study.runs, [run_id]) == [run_id]
    with pytest.raises(InputError, match="did you mean"):
        fr.pick_timeline_runs(study.runs, [run_id[:-1] + "9"])


def test_default_timelines_one_per_behaviour_at_the_highest_spl(study: Any) -> None:
    chosen = fr.pick_timeline_runs(study.runs, None)
    rows = study.runs.set_index("run_id").loc[chosen]
    assert sorted(rows["behaviour"]) == ["lf", "nb"]
    assert set(rows["spl"]) == {50.0}


def test_rssi_runs_pair_ssd_with_esd() -> None:
    runs = pd.DataFrame(
        {
            "run_id": ["s1", "s2", "e1"],
            "threshold": ["ssd", "ssd", "esd"],
            "spl": [0.0, 50.0, 50.0],
            "behaviour": ["lf", "lf", "lf"],
            "repetition": [1, 1, 1],
        }
    )
    rssi = pd.DataFrame(
        {"run_id": ["s1", "s2", "e1"], "t": 0.0, "src": "a", "dst": "b", "rssi": -40.0}
    )
    assert fr.pick_rssi_runs(runs, rssi) == ["s2", "e1"]
    assert fr.pick_rssi_runs(runs, rssi[rssi["run_id"] == "s1"]) == ["s1"]
    assert fr.pick_rssi_runs(runs, rssi.iloc[0:0]) == []


def test_display_and_latex_formatting(study: Any) -> None:
    table = st.comparison_table(study.runs, ["execution_phase_time"])
    shown = tf.display_frame("comparisons", table)
    assert list(shown["configuration"]) == ["AH+SLT+LF", "AH+SLT+NB"]
    assert all(re.fullmatch(r"-?\d+\.\d{2}", z) for z in shown["Z"])
    assert all(
        re.fullmatch(r"-?\d\.\d{2} \[-?\d\.\d{2}, -?\d\.\d{2}\]", r) for r in shown.iloc[:, 13]
    )
    assert set(shown["decision"]) <= {"H_A supported", "H0 not rejected"}
    latex = tf.to_latex("comparisons", table)
    assert r"\begin{tabular}" in latex and r"$\pm$" in latex and "±" not in latex
    assert r"$r=Z/\sqrt{n}$" in latex and "execution\\_phase\\_time" in latex
    # booktabs, a caption, and numbers right-aligned: metric/config/H_A left, m and n right.
    assert r"\toprule" in latex and r"\caption{" in latex
    assert r"\begin{tabular}{lllrr" in latex


def test_a_study_without_finished_runs_is_an_input_error(tmp_path: Path) -> None:
    runs = pd.DataFrame({"run_id": ["a-r001"], "status": ["error"], "error": ["boom"]})
    with pytest.raises(InputError, match="none of the 1 runs finished"):
        rp.build_report(type("Data", (), {"runs": runs})(), tmp_path / "out")
    with pytest.raises(InputError, match="no runs"):
        rp.build_report(type("Data", (), {"runs": runs.iloc[0:0]})(), tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_provenance_of_every_run_is_loaded_and_reported(built: rp.Report, study: Any) -> None:
    from mrcomm.run.provenance import file_hash, git_commit

    runs = study.runs
    assert (runs["mrcomm_version"] == mrcomm.__version__).all()
    assert (runs["git_commit"] == git_commit()).all()  # this checkout's commit (or "")
    assert runs["machine"].str.contains("CPUs").all()
    hashes = json.loads(runs["input_hashes"].iloc[0])
    from tests.conftest import S1_PATH

    assert hashes["scenario"] == file_hash(S1_PATH)
    assert {"scenario", "map", "map_image", "tasks"} <= set(hashes)
    assert runs["fingerprint"].nunique() == len(runs)  # every run its own
    html = built.html.read_text()
    assert "Provenance" in html and hashes["map_image"] in html
    assert f'<td class="text">{mrcomm.__version__}</td>' in html


def test_the_report_defines_its_terms(built: rp.Report) -> None:
    html = built.html.read_text()
    assert 'id="glossary"' in html
    for term in ("SPL", "SLT", "SSD", "ESD", "AON", "execution_phase_time", "Holm"):
        assert term in html.split('id="glossary"', 1)[1], term
    # Every metric the report can show has a unit in the glossary.
    from mrcomm.analysis.glossary import glossary_sections

    named = {str(row[0]) for s in glossary_sections() for row in s.rows if len(row) == 3}
    for metric in st.all_metrics():
        assert any(metric in cell for cell in named), metric
