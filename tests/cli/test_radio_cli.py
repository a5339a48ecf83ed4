"""`mrcomm radio list|show|plot`, and what other commands say of the radio: output,
exit status 2 with a one-line error on bad input, nothing written on error."""

from __future__ import annotations

import json
from pathlib import Path

from mrcomm.net.radio.profile import profile_path
from tests.cli.test_signal_cli import mrcomm

S1 = Path(__file__).parents[2] / "data" / "scenarios" / "s1.yaml"


def test_list_names_every_bundled_profile(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = mrcomm(monkeypatch, capsys, "radio", "list")
    assert code == 0
    assert {line.split(":")[0] for line in out.splitlines()} >= {
        "office-2.4ghz", "corridor-los", "outdoor"
    }  # fmt: skip


def test_show_json_curves_fall_with_distance_and_walls(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = mrcomm(monkeypatch, capsys, "radio", "show", "office-2.4ghz", "--json")
    assert code == 0
    data = json.loads(out)
    curves = {c["walls"]: c["delivery_ratio"] for c in data["curves"]}
    distance = data["distance_m"]
    for ratios in curves.values():
        assert ratios == sorted(ratios, reverse=True)
    los = dict(zip(distance, curves[0], strict=True))
    two = dict(zip(distance, curves[2], strict=True))
    assert los[2.0] >= 0.999 and los[5.0] >= 0.999
    assert two[20.0] < 0.9 and two[30.0] < 0.6


def test_show_prints_a_table(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = mrcomm(monkeypatch, capsys, "radio", "show")
    assert code == 0 and "2 walls" in out and "office-2.4ghz" in out


def test_a_bad_profile_is_one_line(monkeypatch, capsys, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        profile_path("office-2.4ghz").read_text().replace("exponent: 3.0", "exponent: -3")
    )
    code, out, err = mrcomm(monkeypatch, capsys, "radio", "show", str(bad))
    assert code == 2 and not out
    assert err.strip().splitlines() == [
        f"mrcomm: error: {bad}: exponent: must be greater than 0, got -3"
    ]


def test_plot_writes_the_figure_with_a_heat_map(monkeypatch, capsys, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    out_file = tmp_path / "radio.png"
    code, _, err = mrcomm(
        monkeypatch, capsys, "radio", "plot", "--out", str(out_file), "--scenario", str(S1)
    )
    assert code == 0, err
    assert out_file.read_bytes()[:4] == b"\x89PNG"


def test_plot_checks_its_output_before_any_work(monkeypatch, capsys, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    code, _, err = mrcomm(monkeypatch, capsys, "radio", "plot", "--out", str(tmp_path / "x.txt"))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--out" in err
    assert not list(tmp_path.iterdir())
    code, _, err = mrcomm(
        monkeypatch, capsys, "radio", "plot", "--out", str(tmp_path / "y.png"), "--from", "1,2"
    )
    assert code == 2 and "--from needs --scenario" in err


def test_run_prints_the_radio_causes_and_delays(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setenv("COLUMNS", "200")  # the whole message table on one line per topic
    code, out, err = mrcomm(
        monkeypatch, capsys, "run", str(S1), "--network", "radio", "--max-time", "60"
    )
    assert code == 0, err
    assert "packet error (radio)" in out and "mean delay s" in out
