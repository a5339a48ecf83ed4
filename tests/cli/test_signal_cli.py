"""`mrcomm signal fit|show|plot` and `mrcomm pulse` from the command line: output, exit
status 2 with a one-line error on bad input, and nothing written on error."""

from __future__ import annotations

import json
import re
import stat
import sys
from pathlib import Path

import pytest

from mrcomm.cli.main import app
from mrcomm.cli.pulse_cmd import JsonLinesBus, run_pulse
from mrcomm.net.pulse import Pulse
from mrcomm.net.signal.bundled import bundled_calibration_path, default_model_path
from mrcomm.net.signal.svr import load_model

FIXTURES = Path(__file__).parents[1] / "net" / "fixtures"


def mrcomm(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], *args: str
) -> tuple[int, str, str]:
    """Run the console entry point in-process: (exit status, stdout, stderr)."""
    monkeypatch.setattr(sys, "argv", ["mrcomm", *args])
    with pytest.raises(SystemExit) as done:
        app()
    out, err = capsys.readouterr()
    code = done.value.code
    return (code if isinstance(code, int) else 0), out, err


def _small_csv(tmp_path: Path) -> Path:
    rows = ["# my measurements", "distance,rssi,line_of_sight"]
    for los, offset in (("true", 0), ("false", -6)):
        for d in (0.5, 1, 2, 3, 4, 5, 6):
            for k in range(3):
                rows.append(f"{d},{-30 - 5 * d + offset + k - 1},{los}")
    path = tmp_path / "m.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_fit_writes_model_and_prints_summary(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    (tmp_path / "sub").mkdir()
    out = tmp_path / "sub" / "model.json"
    code, stdout, _ = mrcomm(
        monkeypatch, capsys, "signal", "fit", str(_small_csv(tmp_path)), "--out", str(out)
    )
    assert code == 0
    model = load_model(out)
    assert model.line_of_sight.n_samples == 21 and model.provenance["synthetic"] is False
    assert "log-distance fit, line of sight" in stdout
    # −30 − 5 d = −42 at 2.4 m; the smooth SVR is close to it.
    found = re.search(r"line of sight: below at ([0-9.]+) m", stdout)
    assert found is not None and float(found.group(1)) == pytest.approx(2.4, abs=0.1)
    assert [p.name for p in out.parent.iterdir()] == ["model.json"]  # no temp files left


def test_show_text_and_json(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    code, stdout, _ = mrcomm(monkeypatch, capsys, "signal", "show")
    assert code == 0
    assert "SYNTHETIC" in stdout
    assert "line of sight: below at 2.59 m, above at 3.63 m, below at 6.11 m" in stdout
    assert "obstructed: below at 1.60 m" in stdout
    assert "1 m -32.2" in stdout
    code, stdout, _ = mrcomm(
        monkeypatch,
        capsys,
        "signal",
        "show",
        str(default_model_path()),
        "--threshold",
        "-50",
        "--json",
    )
    assert code == 0
    info = json.loads(stdout)
    assert info["threshold_dbm"] == -50.0
    assert [c["direction"] for c in info["line_of_sight"]["crossings"]] == ["below"]
    assert set(info["obstructed"]["rssi_dbm"]) == {"1", "2", "4", "8"}


@pytest.mark.parametrize("suffix", ["png", "svg", "pdf"])
def test_plot_formats(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path, suffix: str
) -> None:
    out = tmp_path / f"model.{suffix}"
    code, _, _ = mrcomm(
        monkeypatch,
        capsys,
        "signal",
        "plot",
        str(default_model_path()),
        "--csv",
        str(bundled_calibration_path()),
        "--out",
        str(out),
    )
    assert code == 0
    head = out.read_bytes()[:8]
    assert {
        "png": head.startswith(b"\x89PNG"),
        "svg": b"<?xml" in head,
        "pdf": head.startswith(b"%PDF"),
    }[suffix]


def test_bad_inputs_exit_2_and_write_nothing(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    bad_csv = tmp_path / "bad.csv"
    bad_csv.write_text("distance,rssi,line_of_sight\n1,-30,true\nx,-31,true\n")
    bad_model = tmp_path / "bad.json"
    bad_model.write_text("{not json")
    out = tmp_path / "out.json"
    fig = tmp_path / "fig.png"
    cases = [
        (("signal", "fit", str(bad_csv), "--out", str(out)), "bad.csv: line 3, column distance"),
        (("signal", "fit", str(tmp_path / "none.csv"), "--out", str(out)), "file not found"),
        (("signal", "show", str(bad_model)), "bad.json: not a JSON signal model"),
        (("signal", "plot", str(bad_model), "--out", str(fig)), "bad.json: not a JSON"),
        (("signal", "plot", "--csv", str(bad_csv), "--out", str(fig)), "bad.csv: line 3"),
        (("signal", "plot", "--out", str(tmp_path / "fig.gif")), "unsupported extension '.gif'"),
        *(
            (
                (
                    "signal",
                    "fit",
                    str(bundled_calibration_path()),
                    "--out",
                    str(out),
                    option,
                    value,
                ),
                f"{option}: must be a finite number",
            )
            for option, value in (("--C", "inf"), ("--epsilon", "inf"), ("--threshold", "nan"))
        ),
    ]
    for args, expected in cases:
        code, _, stderr = mrcomm(monkeypatch, capsys, *args)
        assert code == 2, args
        assert stderr.startswith("mrcomm: error: ") and expected in stderr, stderr
        assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "bad.json"]


def _fake_iw_on_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    dump = FIXTURES / "iw_station_dump_adhoc.txt"
    iw = tmp_path / "bin" / "iw"
    iw.parent.mkdir()
    iw.write_text(
        "#!/bin/sh\n"
        f'[ "$2" = "wlan0" ] || {{ echo "command failed: No such device (-19)" >&2; exit 237; }}\n'
        f"cat {dump}\n"
    )
    iw.chmod(iw.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("PATH", f"{iw.parent}:/usr/bin:/bin")


def test_pulse_prints_json_lines(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    _fake_iw_on_path(tmp_path, monkeypatch)
    code, stdout, stderr = mrcomm(
        monkeypatch,
        capsys,
        "pulse",
        "--iface",
        "wlan0",
        "--peers",
        str(FIXTURES / "peers.yaml"),
        "--robot",
        "robot_1",
        "--count",
        "1",
    )
    assert code == 0, stderr
    lines = [json.loads(line) for line in stdout.splitlines()]
    assert [(r["topic"], r["type"], r["peer"], r["rssi"]) for r in lines] == [
        ("rssi", "rssi", "robot_2", -38.0),
        ("rssi", "rssi", "robot_3", -57.0),
    ]
    assert all(r["robot"] == "robot_1" and r["sender"] == "robot_1-pulse" for r in lines)
    assert "1 polls, 2 readings published" in stderr and "1 unknown stations" in stderr


def test_pulse_start_up_errors(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    _fake_iw_on_path(tmp_path, monkeypatch)
    peers = str(FIXTURES / "peers.yaml")
    code, stdout, stderr = mrcomm(
        monkeypatch, capsys, "pulse", "--iface", "wlan7", "--peers", peers, "--robot", "robot_1"
    )
    assert code == 2 and "No such device" in stderr and stdout == ""
    bad_peers = tmp_path / "peers.yaml"
    bad_peers.write_text("robot_2: 02:00:00\n")
    code, _, stderr = mrcomm(
        monkeypatch, capsys, "pulse", "--iface", "wlan0", "--peers", str(bad_peers), "--robot", "r"
    )
    assert code == 2 and "peers.yaml: robot_2: neither" in stderr
    monkeypatch.setenv("PATH", str(tmp_path))  # no iw at all
    code, _, stderr = mrcomm(
        monkeypatch, capsys, "pulse", "--iface", "wlan0", "--peers", peers, "--robot", "robot_1"
    )
    assert code == 2 and "'iw' command was not found" in stderr


def test_run_pulse_paces_polls_on_the_clock() -> None:
    clock = [100.0]
    slept: list[float] = []

    def sleep(seconds: float) -> None:
        slept.append(seconds)
        clock[0] += seconds

    lines: list[str] = []

    class Sink:
        def write(self, text: str) -> None:
            lines.append(text)

        def flush(self) -> None:
            pass

    bus = JsonLinesBus("robot_1-pulse", Sink())  # type: ignore[arg-type]
    pulse = Pulse(
        bus,
        "robot_1",
        {"02:00:00:00:00:02": "robot_2"},
        lambda: (FIXTURES / "iw_station_dump_adhoc.txt").read_text(),
        period=0.5,
    )
    run_pulse(pulse, count=4, clock=lambda: clock[0], sleep=sleep)
    assert pulse.stats.polls == 4 and pulse.stats.published == 4
    assert slept == pytest.approx([0.5, 0.5, 0.5])
    assert sum('"peer": "robot_2"' in line for line in lines) == 4


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        ((), "--iface: give either --iface (and --peers) or --trace"),
        (("--iface", "wlan0", "--trace", "t.csv"), "give either --iface (and --peers) or --trace"),
        (("--iface", "wlan0"), "--peers: reading the card needs the robots' MAC addresses"),
        (("--trace", "t.csv"), "--trace: a trace is replayed on the world's clock"),
        (
            ("--iface", "wlan0", "--peers", "p.yaml", "--world-connect", "127.0.0.1:7447"),
            "--world-connect: only a replayed --trace runs on the world's clock",
        ),
        (
            ("--trace", "nope.csv", "--connect", "127.0.0.1:7447", "--insecure"),
            "nope.csv: file not found",
        ),
        (
            ("--trace", "t.csv", "--connect", "nowhere", "--insecure"),
            "--connect: bad endpoint 'nowhere'",
        ),
        (("--trace", "t.csv", "--connect", "127.0.0.1:7447"), "--team-dir: no team certificates"),
    ],
)
def test_pulse_source_and_zenoh_errors(
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    args: tuple[str, ...],
    expected: str,
) -> None:
    trace = Path(__file__).parents[2] / "data" / "traces" / "s1_synthetic_esd.csv"
    given = [str(trace) if a == "t.csv" else a for a in args]
    code, stdout, stderr = mrcomm(monkeypatch, capsys, "pulse", "--robot", "robot_1", *given)
    assert code == 2 and stdout == ""
    assert len(stderr.strip().splitlines()) == 1 and expected in stderr, stderr
