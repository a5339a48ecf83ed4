"""Fuzzing the command line itself: seeded random option values (NaN, infinity, 1e308,
negative, empty, words, unknown options and variant parameters) and mutated input files
given to real ``mrcomm`` commands, run in this process. Every case must end with exit
status 0, or 2 with exactly one line on stderr (``mrcomm: error: ...``) and no
traceback — and an exit 2 leaves nothing in the case's output directory. Runs are kept
short (``--max-time`` of a few simulated seconds) so a case that passes validation
costs little. Hypothesis draws the cases from a fixed seed (``derandomize``)."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.conftest import ROOT, S1_PATH
from tests.fuzz.test_fuzz_inputs import _mutate, _s1_text

CASES = 150
VALUES = [
    "nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e-320", "0", "-0", "-1", "1", "2.5",
    "3", "25", "100", "101", "1e9", "99999999999999999999999", "", " ", "abc", "1,2",
    "0x10", "true", "null", "[]", "--json", "-", "é", "\\x00",
]  # fmt: skip
#: Each option with values it accepts: a case draws one of these or an extreme.
RUN_OPTIONS = {
    "--spl": ["0", "25", "50"], "--max-time": ["2", "4"], "--dt": ["0.1", "0.05"],
    "--seed": ["1", "7"], "--network": ["wlan", "ah", "radio"], "--behaviour": ["nb", "lf"],
    "--threshold": ["none", "slt"], "--set": [], "--rssi-trace": [], "--signal-model": [],
    "--plot": [], "--no-such-option": [],
}  # fmt: skip
SETS = [
    "behaviour.pose_period", "behaviour.collision.danger_radius", "threshold.warning",
    "threshold.slt.warning", "network.range", "network.profile", "network.ah.range",
    "behaviour.lf.assign_timeout", "nonsense", "behaviour", "", "threshold.esd.warning_dbm",
]  # fmt: skip


def _cli(monkeypatch: pytest.MonkeyPatch, capsys: Any, args: list[str]) -> tuple[int, str]:
    """Run ``mrcomm ARGS`` in this process: (exit status, stderr)."""
    from mrcomm.cli.main import app

    monkeypatch.setattr(sys, "argv", ["mrcomm", *args])
    capsys.readouterr()
    try:
        app()
        code = 0
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    return code, capsys.readouterr().err


def _check(code: int, err: str, out_dir: Path, args: list[str], seen: list[int]) -> None:
    seen.append(code)
    assert code in (0, 2), (code, args, err[-1500:])
    assert "Traceback" not in err, (args, err[-1500:])
    if code == 2:
        lines = [line for line in err.splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("mrcomm: error:"), (args, err)
        assert list(out_dir.iterdir()) == [], (args, list(out_dir.iterdir()))


def _settings() -> Any:
    return settings(
        max_examples=CASES,
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    )


def _fresh(directory: Path) -> Path:
    shutil.rmtree(directory, ignore_errors=True)
    directory.mkdir(parents=True)
    return directory


def test_run_options_with_random_values(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """``mrcomm run S1`` with one to three options of random value (a short mission
    when they are valid; its figure and database in the case's output directory)."""

    @_settings()
    @given(st.data())
    def case(data: st.DataObject) -> None:
        out = _fresh(tmp_path / "out")
        args = [str(S1_PATH), "--max-time", "3"]
        for _ in range(data.draw(st.integers(1, 3))):
            option = data.draw(st.sampled_from(sorted(RUN_OPTIONS)))
            good = RUN_OPTIONS[option]
            value = data.draw(
                st.sampled_from(good if good and data.draw(st.booleans()) else VALUES)
            )
            if option == "--set":
                value = f"{data.draw(st.sampled_from(SETS))}={value}"
            elif option == "--plot":
                value = str(out / f"fig{data.draw(st.sampled_from(['.png', '.svg', '.txt', '']))}")
            args += [option, value]
        args += data.draw(st.sampled_from([[], ["--json"], ["--db", str(out / "r.duckdb")]]))
        code, err = _cli(monkeypatch, capsys, ["run", *args])
        _check(code, err, out, args, seen)

    seen: list[int] = []
    case()
    # Both outcomes reached: the cases explore from working commands into bad ones.
    assert seen.count(0) >= 5 and seen.count(2) >= 5, (seen.count(0), seen.count(2))


def test_run_on_mutated_scenarios(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """``mrcomm run`` on a mutated scenario file (map and tasks by absolute path)."""
    base = _s1_text()

    @_settings()
    @given(st.data())
    def case(data: st.DataObject) -> None:
        out = _fresh(tmp_path / "out")
        scenario = tmp_path / "scenario.yaml"
        scenario.write_text(_mutate(base, data), encoding="utf-8", errors="surrogatepass")
        args = [str(scenario), "--max-time", "3", "--plot", str(out / "m.png")]
        code, err = _cli(monkeypatch, capsys, ["run", *args])
        _check(code, err, out, args, seen)

    seen: list[int] = []
    case()
    # Both outcomes reached: the cases explore from working commands into bad ones.
    assert seen.count(0) >= 5 and seen.count(2) >= 5, (seen.count(0), seen.count(2))


def test_radio_and_team_commands_with_random_values(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """``radio show|plot`` and ``team init`` with random sizes, names and addresses."""
    profiles = ["office-2.4ghz", "corridor-los", "outdoor", "nope", "", "../x", "nan"]

    @_settings()
    @given(st.data())
    def case(data: st.DataObject) -> None:
        out = _fresh(tmp_path / "out")
        kind = data.draw(st.sampled_from(["show", "plot", "team"]))
        value = data.draw(st.sampled_from(VALUES))
        if kind == "show":
            args = ["radio", "show", data.draw(st.sampled_from(profiles)), "--bytes", value]
        elif kind == "plot":
            name = data.draw(st.sampled_from(["r.png", "r.txt", "d/r.png"]))
            args = ["radio", "plot", data.draw(st.sampled_from(profiles)), "--out", str(out / name)]
        else:
            members = data.draw(st.sampled_from(["robot_1", "a/b", "ca", "r,r", "", value]))
            args = ["team", "init", str(out / "team"), "--members", members,
                    "--days", data.draw(st.sampled_from(["1", "0", "-1", "99999", value])),
                    "--address", f"robot_1={value}"]  # fmt: skip
        code, err = _cli(monkeypatch, capsys, args)
        _check(code, err, out, args, seen)

    seen: list[int] = []
    case()
    # Both outcomes reached: the cases explore from working commands into bad ones.
    assert seen.count(0) >= 5 and seen.count(2) >= 5, (seen.count(0), seen.count(2))


def test_results_commands_on_damaged_databases(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """``analyze``, ``report`` and ``export`` on a file that is no results database:
    random bytes, a text file, a truncated header — one line, nothing written."""
    magic = b"\x00" * 8 + b"DUCK"

    @_settings()
    @given(st.data())
    def case(data: st.DataObject) -> None:
        out = _fresh(tmp_path / "out")
        db = tmp_path / "in.duckdb"
        body = data.draw(st.sampled_from([b"", b"not a database\n", magic]))
        db.write_bytes(body + data.draw(st.binary(max_size=300)))
        command = data.draw(st.sampled_from(["analyze", "report", "export"]))
        if command == "analyze":
            args = ["analyze", "--db", str(db)]
        elif command == "report":
            args = ["report", "--db", str(db), "--out", str(out / "rep")]
        else:
            args = ["export", "--db", str(db), "--out", str(out / "csv")]
        code, err = _cli(monkeypatch, capsys, args)
        _check(code, err, out, args, seen)

    seen: list[int] = []
    case()
    assert set(seen) == {2}  # never accepted as a database


def test_the_fuzzed_commands_accept_their_base_case(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """The starting points run (so the fuzzing above explores from working commands)."""
    out = tmp_path / "out"
    out.mkdir()
    code, err = _cli(monkeypatch, capsys, ["run", str(S1_PATH), "--max-time", "3", "--json"])
    assert code == 0, err
    code, err = _cli(monkeypatch, capsys, ["radio", "show", "office-2.4ghz", "--bytes", "150"])
    assert code == 0, err
    code, err = _cli(monkeypatch, capsys, ["team", "init", str(out / "t"), "--members", "r"])
    assert code == 0, err
    assert (ROOT / "data" / "scenarios" / "s1.yaml").is_file()
