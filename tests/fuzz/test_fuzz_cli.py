"""Fuzzing the command line itself: seeded random option values (NaN, infinity, 1e308,
negative, empty, words, unknown options and variant parameters) and mutated input files
(scenarios, maps, task files, experiment schemas, calibration sets, signal models: the
mutations of ``test_fuzz_inputs.py``) given to real ``mrcomm`` commands — ``run``,
``sweep``, ``signal fit|show|plot``, ``check``, ``radio show|plot``, ``team init`` and
the results commands — run in this process. Every case must end with exit status 0, or
2 with exactly one line on stderr (``mrcomm: error: ...``) and no traceback — and an
exit 2 leaves nothing in the case's output directory. Runs are kept short
(``--max-time`` of a few simulated seconds, sweeps of a few runs) so a case that passes
validation costs little. Hypothesis draws the cases from a fixed seed (``derandomize``):
1,050 cases, about 40 s with ``pytest -n 2`` on two cores."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.conftest import ROOT, S1_PATH
from tests.fuzz.test_fuzz_inputs import BASES, EXTREMES, _mutate, _s1_text

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


def _assert_both_outcomes(seen: list[int]) -> None:
    """Both outcomes reached: the cases explore from working commands into bad ones."""
    assert seen.count(0) >= 5 and seen.count(2) >= 5, (seen.count(0), seen.count(2))


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
    _assert_both_outcomes(seen)


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
    _assert_both_outcomes(seen)


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
    _assert_both_outcomes(seen)


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


#: Option values of the commands below: the command-line extremes and the YAML ones.
ANY = list(dict.fromkeys(VALUES + EXTREMES))
#: A sweep of 3 configurations of 2 simulated seconds, one repetition each.
SCHEMA = f"""\
name: fz
scenario: {S1_PATH}
repetitions: 1
base_seed: 3
factors: {{spl: [0, 50], behaviour: [nb, lf]}}
exclude: [{{spl: 50, behaviour: nb}}]
options: {{network: wlan, threshold: none, max_time: 2}}
"""
#: Each sweep option with values it accepts. Small --run-timeout values are left out:
#: they are valid and make runs time out (exit 1, failed runs) depending on the
#: machine's speed.
SWEEP_OPTIONS = {
    "--reps": ["1", "2"], "--jobs": ["1", "2"], "--run-timeout": ["100", "1e9"],
    "--connect-timeout": ["5", "0.5"], "--set": [], "--record": [], "--db": [],
    "--no-such-option": [],
}  # fmt: skip
TOO_SHORT = {"1e-320", "1", "2.5", "3"}


def _sweep_cheaply(monkeypatch: pytest.MonkeyPatch) -> None:
    """Sweeps that pass validation stay cheap: runs in threads of this process (a
    process pool would start interpreters), and at most 6 runs a sweep (the run-count
    check itself, with a small limit: a mutated ``repetitions: 1_000`` is refused)."""
    from concurrent.futures import ThreadPoolExecutor

    from mrcomm.experiment import runner, schema

    monkeypatch.setattr(runner, "process_pool", lambda jobs: ThreadPoolExecutor(jobs))
    monkeypatch.setattr(schema, "MAX_RUNS", 6)


def test_sweep_with_random_options_and_mutated_schemas(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """``mrcomm sweep`` on the schema, mutated or not, with one to three options of
    random value; the database (and recordings) in the case's output directory."""
    _sweep_cheaply(monkeypatch)

    @_settings()
    @given(st.data())
    def case(data: st.DataObject) -> None:
        out = _fresh(tmp_path / "out")
        schema = tmp_path / "fz.yaml"
        text = _mutate(SCHEMA, data) if data.draw(st.booleans()) else SCHEMA
        schema.write_text(text, encoding="utf-8", errors="surrogatepass")
        # --db first, in the output directory: a drawn --db comes later and wins.
        args = [str(schema), "--db", str(out / "r.duckdb")]
        for _ in range(data.draw(st.integers(0, 3))):
            option = data.draw(st.sampled_from(sorted(SWEEP_OPTIONS)))
            good = SWEEP_OPTIONS[option]
            bad = [v for v in ANY if option != "--run-timeout" or v not in TOO_SHORT]
            value = data.draw(st.sampled_from(good if good and data.draw(st.booleans()) else bad))
            if option == "--set":
                value = f"{data.draw(st.sampled_from(SETS))}={value}"
            elif option in ("--db", "--record"):
                name = data.draw(st.sampled_from(["r.duckdb", "r.db", "r.txt", "d/x", value]))
                value = str(out / name)
            args += [option, value]
        code, err = _cli(monkeypatch, capsys, ["sweep", *args])
        _check(code, err, out, args, seen)

    seen: list[int] = []
    case()
    _assert_both_outcomes(seen)


def test_run_on_mutated_maps_and_task_files(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """``mrcomm run`` on S1 with a mutated map YAML or task file (the image intact)."""
    tasks_file = str(S1_PATH.parent / "s1_tasks.yaml")
    office = str(ROOT / "data" / "maps" / "office.yaml")

    @_settings()
    @given(st.data())
    def case(data: st.DataObject) -> None:
        out = _fresh(tmp_path / "out")
        kind = data.draw(st.sampled_from(["map", "tasks"]))
        mutated = tmp_path / f"{kind}.yaml"
        mutated.write_text(_mutate(BASES[kind][0], data), encoding="utf-8", errors="surrogatepass")
        scenario = tmp_path / "scenario.yaml"
        scenario.write_text(
            _s1_text().replace(office if kind == "map" else tasks_file, str(mutated))
        )
        args = [str(scenario), "--max-time", "3", "--plot", str(out / "m.png")]
        code, err = _cli(monkeypatch, capsys, ["run", *args])
        _check(code, err, out, args, seen)

    seen: list[int] = []
    case()
    _assert_both_outcomes(seen)


def test_signal_and_check_commands_with_random_values(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """``signal fit`` on a mutated calibration set (a third of the bundled one) with a
    random hyper-parameter, ``signal show|plot`` of a mutated model with a random
    threshold, ``check`` of random variant and check names (only the cheap ``api``
    check ever runs)."""
    from mrcomm.specs import REGISTRY

    variants = [s.key for s in REGISTRY.all()] + ["lf", "nb", "behaviour.", ".lf", "nope"]
    #: Each option with values it accepts (--config and --map: not with a CSV).
    fit_options = {
        "--gamma": ["0.1", "1"], "--C": ["100", "10"], "--epsilon": ["0.1", "0"],
        "--threshold": ["-42", "-60"], "--config": [], "--map": [], "--bad": [],
    }  # fmt: skip

    @_settings()
    @given(st.data())
    def case(data: st.DataObject) -> None:
        out = _fresh(tmp_path / "out")
        kind = data.draw(st.sampled_from(["fit", "show", "plot", "check"]))
        value = data.draw(st.sampled_from(ANY))
        # Half the files and values are left as they work: the cases explore from
        # working commands into bad ones.
        kept = data.draw(st.booleans())
        if kind == "fit":
            csv = tmp_path / "calibration.csv"
            text = BASES["calibration"][0]
            csv.write_text(text if kept else _mutate(text, data),
                           encoding="utf-8", errors="surrogatepass")  # fmt: skip
            name = data.draw(st.sampled_from(["m.json", "m.json", "m.txt", "d/m.json"]))
            option = data.draw(st.sampled_from(sorted(fit_options)))
            good = fit_options[option]
            if good and data.draw(st.booleans()):
                value = data.draw(st.sampled_from(good))
            args = ["signal", "fit", str(csv), "--out", str(out / name), option, value]
        elif kind in ("show", "plot"):
            model = tmp_path / "model.json"
            text = BASES["model"][0]
            model.write_text(text if kept else _mutate(text, data),
                             encoding="utf-8", errors="surrogatepass")  # fmt: skip
            if data.draw(st.booleans()):
                value = data.draw(st.sampled_from(["-42", "-60.5"]))
            args = ["signal", kind, str(model), "--threshold", value]
            if kind == "plot":
                name = data.draw(st.sampled_from(["s.png", "s.svg", "s.txt"]))
                args += ["--out", str(out / name)]
            else:
                args += data.draw(st.sampled_from([[], ["--json"]]))
        else:
            target = data.draw(st.sampled_from([[v] for v in variants] + [[value], ["--all"]]))
            only = data.draw(st.sampled_from(["api", value]))
            args = ["check", *target, "--only", only]
        code, err = _cli(monkeypatch, capsys, args)
        _check(code, err, out, args, seen)

    seen: list[int] = []
    case()
    _assert_both_outcomes(seen)


def test_the_new_fuzzed_commands_accept_their_base_case(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path
) -> None:
    """The starting points of the sweep, signal and check fuzzing run."""
    _sweep_cheaply(monkeypatch)
    schema = tmp_path / "fz.yaml"
    schema.write_text(SCHEMA)
    calibration = tmp_path / "calibration.csv"
    calibration.write_text(BASES["calibration"][0])
    model = tmp_path / "model.json"
    model.write_text(BASES["model"][0])
    for args in (
        ["sweep", str(schema), "--db", str(tmp_path / "r.duckdb"), "--reps", "2"],
        ["signal", "fit", str(calibration), "--out", str(tmp_path / "m.json")],
        ["signal", "show", str(model), "--threshold", "-42"],
        ["check", "behaviour.lf", "--only", "api"],
    ):
        code, err = _cli(monkeypatch, capsys, args)
        assert code == 0, (args, err)


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        # scikit-learn's SVR has no iteration limit: C 1e308 never finished.
        (["signal", "fit", "CAL", "--out", "OUT/m.json", "--C", "1e308"], "--C: must be at most"),
        # Dask parses the timeout as text: NaN and infinity were a KeyError traceback,
        # a negative one was reported as an unreachable scheduler.
        (["sweep", "SCHEMA", "--db", "OUT/r.duckdb", "--connect-timeout", "nan"], "--connect-"),
        (
            ["sweep", "SCHEMA", "--db", "OUT/r.duckdb", "--scheduler", "tcp://127.0.0.1:9",
             "--connect-timeout", "inf"],
            "--connect-timeout: must be a positive number of seconds, got inf",
        ),
        (
            ["sweep", "SCHEMA", "--db", "OUT/r.duckdb", "--scheduler", "tcp://127.0.0.1:9",
             "--connect-timeout", "-1"],
            "--connect-timeout: must be a positive number of seconds, got -1",
        ),
    ],
)  # fmt: skip
def test_what_the_fuzzing_found(
    monkeypatch: pytest.MonkeyPatch, capsys: Any, tmp_path: Path, args: list[str], needle: str
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    schema = tmp_path / "fz.yaml"
    schema.write_text(SCHEMA)
    calibration = tmp_path / "calibration.csv"
    calibration.write_text(BASES["calibration"][0])
    places = {"CAL": str(calibration), "SCHEMA": str(schema)}
    args = [places.get(a, a.replace("OUT", str(out))) for a in args]
    code, err = _cli(monkeypatch, capsys, args)
    _check(code, err, out, args, [])
    assert code == 2 and needle in err, err
