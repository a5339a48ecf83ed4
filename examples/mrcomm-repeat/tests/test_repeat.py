"""The example plugin, as its author would test it: MRComm finds it, runs it with its
parameter, sweeps it as a factor, and it passes MRComm's conformance kit."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from mrcomm.specs import get_spec
from mrcomm.testing import CHECKS, check_variant
from mrcomm.testing.checks import S1


def mrcomm(*args: str) -> subprocess.CompletedProcess[str]:
    code = "from mrcomm.cli.main import app; app()"
    return subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=600
    )


def test_mrcomm_lists_the_plugin_with_its_parameter() -> None:
    done = mrcomm("variants", "behaviour", "--json")
    assert done.returncode == 0, done.stderr
    rows = {r["name"]: r for r in json.loads(done.stdout)}
    repeat = rows["repeat"]
    assert repeat["origin"] == "mrcomm-repeat"
    params = {p["key"]: p for p in repeat["parameters"]}
    assert params["behaviour.repeats"]["default"] == 3
    assert "behaviour.pose_period" in params  # NB's parameters come with it


def test_one_repeat_is_exactly_nb() -> None:
    def run(behaviour: str, **params: int) -> dict[str, object]:
        config = make_config(
            None, scenario=S1, behaviour=behaviour, spl=50, seed=2,
            params={"behaviour": params} if params else {},
        )  # fmt: skip
        summary = run_mission(config).summary()
        summary.pop("wall_time_s")
        summary.pop("config")
        # Its own metric (no copy with one repeat) is the only difference.
        if summary["mission"].pop("status_copies", None) is not None:
            for robot in summary["robots"].values():
                assert robot.pop("status_copies") == 0
        return summary

    assert run("repeat", repeats=1) == run("nb")


def test_repeats_are_published_and_lose_fewer_statuses_than_nb() -> None:
    args = ["run", str(S1), "--spl", "50", "--json"]
    failed = {"nb": 0, "repeat": 0}
    for seed in ("1", "2", "3", "4"):
        nb = json.loads(mrcomm(*args, "--seed", seed).stdout)
        rep = mrcomm(*args, "--seed", seed, "--behaviour", "repeat", "--set", "behaviour.repeats=4")
        assert rep.returncode == 0, rep.stderr
        repeat = json.loads(rep.stdout)
        assert repeat["config"]["params"] == {"behaviour": {"repeats": 4}}
        # 7 successes x 4 copies + one AGENDA_COMPLETE per robot.
        assert repeat["messages"]["task_status"]["sent"] == 7 * 4 + 3
        failed["nb"] += len(nb["mission"]["failed_tasks"])
        failed["repeat"] += len(repeat["mission"]["failed_tasks"])
    assert failed["repeat"] < failed["nb"], failed


def test_a_bad_parameter_is_a_one_line_error() -> None:
    done = mrcomm("run", str(S1), "--behaviour", "repeat", "--set", "behaviour.repeats=0")
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0
    assert "--set behaviour.repeats" in done.stderr


def sweep(folder: Path, repetitions: int, seed: int, factors: str, jobs: int) -> Path:
    """``mrcomm sweep`` of S1 with ``factors`` into a new database (its path)."""
    schema = folder / "study.yaml"
    schema.write_text(
        f"scenario: {S1}\nrepetitions: {repetitions}\nbase_seed: {seed}\nfactors: {factors}\n"
    )
    db = folder / "study.duckdb"
    done = mrcomm("sweep", str(schema), "--db", str(db), "--jobs", str(jobs))
    assert done.returncode == 0, done.stderr
    return db


def test_a_sweep_takes_the_parameter_as_a_factor(tmp_path: Path) -> None:
    factors = "{behaviour: [repeat], spl: [50], behaviour.repeats: [1, 3]}"
    db = sweep(tmp_path, 2, 3, factors, jobs=1)
    from mrcomm.experiment.api import load_results

    results = load_results(db)
    labels = sorted(results.configs["label"])
    assert labels == ["WLAN_REPEAT_SPL50_REPEATS1", "WLAN_REPEAT_SPL50_REPEATS3"]
    assert len(results.runs) == 4


@pytest.mark.parametrize("check", list(CHECKS))
def test_the_plugin_passes_mrcomms_conformance_kit(check: str) -> None:
    (result,) = check_variant(get_spec("behaviour", "repeat"), only=[check])
    assert result.passed, result.detail


def test_its_team_metric_is_stored_analysed_and_drawn(tmp_path: Path) -> None:
    """The plugin's team metric (declared in its spec, no MRComm file edited) is a
    column of the results, a metric ``mrcomm analyze`` tests and a figure of
    ``mrcomm report``."""
    factors = "{behaviour: [repeat], spl: [0, 50], behaviour.repeats: [2, 3]}"
    db = sweep(tmp_path, 3, 4, factors, jobs=2)
    from mrcomm.experiment.api import load_results

    runs = load_results(db).runs
    # 7 successes, repeats - 1 copies each.
    copies = runs.groupby("label")["status_copies"].agg(set).to_dict()
    assert copies == {
        "WLAN_REPEAT_SPL0_REPEATS2": {7.0},
        "WLAN_REPEAT_SPL50_REPEATS2": {7.0},
        "WLAN_REPEAT_SPL0_REPEATS3": {14.0},
        "WLAN_REPEAT_SPL50_REPEATS3": {14.0},
    }
    done = mrcomm("analyze", "--db", str(db), "--metric", "status_copies", "--format", "csv")
    assert done.returncode == 0, done.stderr
    assert "status_copies" in done.stdout
    out = tmp_path / "report"
    done = mrcomm("report", "--db", str(db), "--out", str(out))
    assert done.returncode == 0, done.stderr
    html = (out / "report.html").read_text()
    assert "Status copies sent" in html
    assert list(out.rglob("metric_status_copies.*")), sorted(p.name for p in out.rglob("*"))
