"""`mrcomm radio fit` and `mrcomm signal fit` from a results database or a readings CSV:
a profile fitted to a simulated run's own RSSI comes out near the profile the run
simulated; bad input is one line on stderr, exit status 2, and nothing written."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest

from mrcomm.experiment.adhoc import store_result
from mrcomm.net.radio.profile import load_profile
from mrcomm.net.signal.svr import load_model
from mrcomm.run.config import make_config
from mrcomm.sim.mission import run_mission
from tests.cli.test_signal_cli import mrcomm
from tests.conftest import S1_PATH
from tests.net.test_radio_fit import MAP, draw_readings, true_profile, write_readings_csv

ESD_LABEL = "RADIO_NB_SPL0_ESD"
SSD_LABEL = "RADIO_LF_SPL0_SSD"


def _run(s1_resources: Any, **options: Any) -> Any:
    values = {"network": "radio", "behaviour": "nb", "seed": 1, "max_time": 200.0, **options}
    return run_mission(make_config(None, scenario=S1_PATH, **values), s1_resources)


@pytest.fixture(scope="module")
def databases(tmp_path_factory: pytest.TempPathFactory, s1_resources: Any) -> dict[str, Path]:
    """``mixed``: a 200 s NB mission whose robots' pulses measured the office radio
    (ESD, no trace) and a short SSD mission; ``ssd``: the SSD one only; ``silent``: an
    ESD run without RSSI rows."""
    folder = tmp_path_factory.mktemp("dbs")
    esd = _run(s1_resources, threshold="esd", params={"threshold": {"warning_dbm": -70.0}})
    ssd = _run(s1_resources, threshold="ssd", behaviour="lf", max_time=20.0)
    out = {name: folder / f"{name}.duckdb" for name in ("mixed", "ssd", "silent")}
    store_result(out["mixed"], esd)
    store_result(out["mixed"], ssd)
    store_result(out["ssd"], ssd)
    store_result(out["silent"], dataclasses.replace(esd, rssi_series=[]))
    return out


def test_a_profile_fitted_to_a_simulated_run_is_near_the_one_it_simulated(
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    databases: dict[str, Path],
    tmp_path: Path,
) -> None:
    out = tmp_path / "fitted.yaml"
    code, stdout, err = mrcomm(
        monkeypatch, capsys, "radio", "fit", str(databases["mixed"]), "--out", str(out), "--json"
    )
    assert code == 0, err
    data = json.loads(stdout)
    # One run (the SSD run's RSSI is a model prediction: left out), office-2.4ghz's
    # profile as the base: L0 40, n 3.0, 6 dB per wall, σ 6 dB over 5 m.
    assert data["groups"] == 1 and data["readings"] > 2000 and data["base"] == "office-2.4ghz"
    assert 1.5 < data["exponent"]["value"] < 4.5
    assert 3.0 < data["shadowing_sigma_db"]["value"] < 9.0
    assert 30.0 < data["reference_loss_db"]["value"] < 50.0
    assert 3.0 < data["wall_loss_db"]["value"] < 9.0
    assert data["r_squared"] > 0.8
    lo, hi = data["exponent"]["ci95"]
    assert lo < data["exponent"]["value"] < hi
    assert any(ESD_LABEL in n for n in data["notes"])
    profile = load_profile(out)
    assert profile.name == "fitted" and profile.exponent == data["exponent"]["value"]
    assert "simulated run(s) of " + ESD_LABEL in profile.source
    assert profile.rate_bps == load_profile("office-2.4ghz").rate_bps
    # The same runs chosen by label; a text summary.
    again = tmp_path / "again.yaml"
    code, stdout, _ = mrcomm(
        monkeypatch, capsys, "radio", "fit", str(databases["mixed"]), "--out", str(again),
        "--config", ESD_LABEL,
    )  # fmt: skip
    assert code == 0
    assert "exponent" in stdout and "95 % CI" in stdout and f"wrote {again}" in stdout
    assert load_profile(again).exponent == profile.exponent


def test_signal_fit_builds_the_calibration_set_from_the_esd_runs(
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    databases: dict[str, Path],
    tmp_path: Path,
) -> None:
    out = tmp_path / "ssd-model.json"
    code, stdout, err = mrcomm(
        monkeypatch, capsys, "signal", "fit", str(databases["mixed"]), "--out", str(out)
    )
    assert code == 0, err
    model = load_model(out)
    assert model.provenance["synthetic"] is True  # simulated runs
    assert model.line_of_sight.n_samples >= 10 and model.obstructed.n_samples >= 10
    assert "SYNTHETIC calibration" in stdout and "log-distance fit, obstructed" in stdout
    # Obstructed links are weaker than clear ones at the same distance.
    assert model.curve(True).predict(5.0) > model.curve(False).predict(5.0)


def test_a_readings_csv_with_its_map(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    readings = draw_readings(true_profile(), seeds=(3,), steps=120)
    csv = tmp_path / "readings.csv"
    write_readings_csv(csv, readings, len(readings))
    out = tmp_path / "lab.yaml"
    code, stdout, err = mrcomm(
        monkeypatch, capsys, "radio", "fit", str(csv), "--map", str(MAP), "--out", str(out),
        "--tx-power", "15", "--name", "my-lab", "--json",
    )  # fmt: skip
    assert code == 0, err
    data = json.loads(stdout)
    profile = load_profile(out)
    assert profile.name == "my-lab" and profile.tx_power_dbm == 15.0
    assert profile.reference_loss_db == pytest.approx(
        15.0 - data["intercept_dbm"]["value"], abs=1e-2
    )
    assert data["asymmetry_db"]["status"] == "kept"  # a CSV does not name robot pairs
    assert 1.5 < data["exponent"]["value"] < 4.0


def _csv(tmp_path: Path, text: str, name: str = "r.csv") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


ERRORS: list[tuple[str, list[str], str]] = [
    ("csv without a map", ["radio", "fit", "{csv}", "--out", "{out}"], "needs --map MAP.yaml"),
    (
        "config of a csv",
        ["radio", "fit", "{csv}", "--map", "{map}", "--config", "X", "--out", "{out}"],
        "--config: --config selects runs of a results database",
    ),
    (
        "unknown label",
        ["radio", "fit", "{mixed}", "--config", "RADIO_NB_SPL0_ESX", "--out", "{out}"],
        f"--config: no configuration labelled 'RADIO_NB_SPL0_ESX' (did you mean '{ESD_LABEL}'?)",
    ),
    (
        "ssd label",
        ["radio", "fit", "{mixed}", "--config", SSD_LABEL, "--out", "{out}"],
        "uses SSD: its RSSI is the SVR model's prediction, not a measurement",
    ),
    ("only ssd runs", ["radio", "fit", "{ssd}", "--out", "{out}"], "no run measured RSSI"),
    ("no rssi rows", ["radio", "fit", "{silent}", "--out", "{out}"], "no RSSI readings in"),
    ("wrong suffix", ["radio", "fit", "{json}", "--out", "{out}"], "unsupported extension '.json'"),
    ("missing source", ["radio", "fit", "{missing}", "--out", "{out}"], "file not found"),
    ("out suffix", ["radio", "fit", "{mixed}", "--out", "{bad_out}"], "unsupported extension"),
    ("out directory", ["radio", "fit", "{mixed}", "--out", "{lost_out}"], "does not exist"),
    (
        "missing column",
        ["radio", "fit", "{no_rssi}", "--map", "{map}", "--out", "{out}"],
        "missing column 'rssi'",
    ),
    (
        "too few readings",
        ["radio", "fit", "{few}", "--map", "{map}", "--out", "{out}"],
        "only 3 usable readings, need at least 30",
    ),
    (
        "tx power",
        ["radio", "fit", "{mixed}", "--tx-power", "50", "--out", "{out}"],
        "--tx-power: must be -30 to 36 dBm",
    ),
    (
        "unknown base",
        ["radio", "fit", "{mixed}", "--base", "ofice-2.4ghz", "--out", "{out}"],
        "did you mean 'office-2.4ghz'",
    ),
    (
        "signal: ssd label",
        ["signal", "fit", "{mixed}", "--config", SSD_LABEL, "--out", "{model}"],
        "uses SSD",
    ),
    ("signal: only ssd", ["signal", "fit", "{ssd}", "--out", "{model}"], "no run measured RSSI"),
    (
        "signal: config of a csv",
        ["signal", "fit", "{calibration}", "--config", ESD_LABEL, "--out", "{model}"],
        "--config: applies to a results database",
    ),
    ("signal: out suffix", ["signal", "fit", "{mixed}", "--out", "{out}"], "unsupported extension"),
]


@pytest.mark.parametrize(("case", "args", "message"), ERRORS, ids=[e[0] for e in ERRORS])
def test_bad_input_is_one_line_exit_2_and_nothing_written(
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    databases: dict[str, Path],
    tmp_path: Path,
    case: str,
    args: list[str],
    message: str,
) -> None:
    outputs = tmp_path / "outputs"
    outputs.mkdir()
    names = {
        **{k: str(v) for k, v in databases.items()},
        "map": str(MAP),
        "out": str(outputs / "p.yaml"),
        "model": str(outputs / "m.json"),
        "bad_out": str(outputs / "p.json"),
        "lost_out": str(tmp_path / "nowhere" / "p.yaml"),
        "missing": str(tmp_path / "absent.duckdb"),
        "json": _csv(tmp_path, "{}", "r.json"),
        "csv": _csv(tmp_path, "x_tx,y_tx,x_rx,y_rx,rssi\n10,10,12,10,-40\n"),
        "no_rssi": _csv(tmp_path, "x_tx,y_tx,x_rx,y_rx\n10,10,12,10\n", "n.csv"),
        "few": _csv(
            tmp_path,
            "x_tx,y_tx,x_rx,y_rx,rssi\n10,10,12,10,-40\n10,10,14,10,-45\n10,10,16,10,-47\n",
            "few.csv",
        ),
        "calibration": _csv(tmp_path, "distance,rssi,line_of_sight\n1,-30,true\n", "c.csv"),
    }
    code, stdout, err = mrcomm(monkeypatch, capsys, *(a.format(**names) for a in args))
    assert code == 2, (case, stdout, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mrcomm: error: "), err
    assert message in lines[0], lines[0]
    assert "Traceback" not in err
    assert list(outputs.iterdir()) == []


def test_a_fitted_value_outside_a_profiles_limits_is_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # Readings 60 dB stronger than a 10 dBm radio could give: L0 would be negative.
    readings = draw_readings(true_profile(), seeds=(3,), steps=60)
    loud = dataclasses.replace(readings, rssi=readings.rssi + 60.0)
    csv = tmp_path / "loud.csv"
    write_readings_csv(csv, loud, len(loud))
    out = tmp_path / "loud.yaml"
    code, _, err = mrcomm(
        monkeypatch, capsys, "radio", "fit", str(csv), "--map", str(MAP), "--out", str(out)
    )
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "the fitted reference_loss_db = -" in err and "(is --tx-power right?)" in err
    assert not out.exists()
