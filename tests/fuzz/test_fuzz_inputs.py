"""Fuzzing every input file MRComm reads: seeded random mutations of real files — a
number swapped for NaN, infinity, 1e308, a string, a list; lines deleted, duplicated,
swapped; random text inserted; the file cut short — fed to the loader each CLI
command uses. Each must load or raise one :class:`InputError` (the CLI prints it as
one line, exit status 2): never another exception (a traceback), never a file written.
Hypothesis draws the cases from a fixed seed (``derandomize``), so every run of the
suite tries the same ones; ``CASES`` per kind, over 1,000 in all."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mrcomm.errors import InputError
from tests.conftest import ROOT, S1_PATH

CASES = 150
EXTREMES = [
    "nan", ".nan", "inf", "-inf", ".inf", "1e308", "-1.0e+308", "1e-320", "0", "-1",
    "99999999999999999999999", "true", "null", "''", "[]", "{}", "abc", "[1, [2, [3]]]",
    "&a x", "*a", "!!python/object:os.system", "\"\\u0000\"", "0x1F", "1_000",
]  # fmt: skip
NUMBER = re.compile(r"(?<![\w.])-?\d+(\.\d+)?([eE][-+]?\d+)?(?![\w.])")


def _mutate(text: str, data: st.DataObject) -> str:
    """One to three random edits of ``text``."""
    for _ in range(data.draw(st.integers(1, 3))):
        lines = text.splitlines()
        op = data.draw(st.sampled_from(["number", "delete", "dup", "swap", "insert", "cut"]))
        if op == "number":
            spots = list(NUMBER.finditer(text))
            if spots:
                m = data.draw(st.sampled_from(spots))
                text = text[: m.start()] + data.draw(st.sampled_from(EXTREMES)) + text[m.end() :]
        elif op in ("delete", "dup", "swap") and lines:
            i = data.draw(st.integers(0, len(lines) - 1))
            j = data.draw(st.integers(0, len(lines) - 1))
            if op == "delete":
                del lines[i]
            elif op == "dup":
                lines.insert(i, lines[i])
            else:
                lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines) + "\n"
        elif op == "insert":
            at = data.draw(st.integers(0, len(text)))
            junk = data.draw(st.text(max_size=20))
            text = text[:at] + junk + text[at:]
        else:
            text = text[: data.draw(st.integers(0, len(text)))]
    return text


def _fuzz(base: str, suffix: str, load: Callable[[Path], Any], tmp: Path, data: Any) -> None:
    path = tmp / f"input{suffix}"
    text = _mutate(base, data)
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    before = sorted(p.name for p in tmp.iterdir())
    try:
        load(path)
    except InputError as err:
        line = err.one_line()
        assert "\n" not in line and len(line) < 2000, line
    assert sorted(p.name for p in tmp.iterdir()) == before  # nothing written


def _s1_text() -> str:
    return (
        S1_PATH.read_text()
        .replace("../maps/office.yaml", str(ROOT / "data" / "maps" / "office.yaml"))
        .replace("s1_tasks.yaml", str(S1_PATH.parent / "s1_tasks.yaml"))
    )


def _load_scenario(path: Path) -> Any:
    from mrcomm.world.scenario import load_scenario

    return load_scenario(path)


def _load_tasks(path: Path) -> Any:
    """The scenario S1 with ``path`` as its task file."""
    from mrcomm.world.scenario import load_scenario

    scenario = path.with_name("scenario.yaml")
    scenario.write_text(_s1_text().replace(str(S1_PATH.parent / "s1_tasks.yaml"), str(path)))
    try:
        return load_scenario(scenario)
    finally:
        scenario.unlink()


def _load_map(path: Path) -> Any:
    from mrcomm.world.mapio import load_map

    return load_map(path)


def _load_experiment(path: Path) -> Any:
    from mrcomm.experiment.schema import load_experiment

    return load_experiment(path)


def _load_model(path: Path) -> Any:
    from mrcomm.net.signal.svr import load_model

    return load_model(path)


def _load_trace(path: Path) -> Any:
    from mrcomm.net.signal.trace import RssiTrace

    return RssiTrace.load(path)


def _load_profile(path: Path) -> Any:
    from mrcomm.net.radio.profile import load_profile

    return load_profile(str(path))


def _load_calibration(path: Path) -> Any:
    from mrcomm.net.signal.calibration import load_calibration

    return load_calibration(path)


def _bases() -> dict[str, tuple[str, str, Callable[[Path], Any]]]:
    from mrcomm.net.radio.profile import profile_path
    from mrcomm.net.signal.bundled import bundled_calibration_path, default_model_path

    office = ROOT / "data" / "maps" / "office.yaml"
    model = default_model_path().read_text()
    trace = (ROOT / "data" / "traces" / "s1_synthetic_esd.csv").read_text().splitlines()
    calibration = bundled_calibration_path().read_text().splitlines()
    experiment = (ROOT / "data" / "experiments" / "radio.yaml").read_text()
    return {
        "scenario": (_s1_text(), ".yaml", _load_scenario),
        "tasks": ((S1_PATH.parent / "s1_tasks.yaml").read_text(), ".yaml", _load_tasks),
        "map": (
            office.read_text().replace("office.pgm", str(office.parent / "office.pgm")),
            ".yaml",
            _load_map,
        ),
        "experiment": (
            experiment.replace("../scenarios/s1.yaml", str(S1_PATH)),
            ".yaml",
            _load_experiment,
        ),
        "model": (model, ".json", _load_model),
        "trace": ("\n".join(trace[:400]) + "\n", ".csv", _load_trace),
        "profile": (profile_path("office-2.4ghz").read_text(), ".yaml", _load_profile),
        "calibration": (_every_third(calibration), ".csv", _load_calibration),
    }


def _every_third(lines: list[str]) -> str:
    """The header and comments, and every third reading (both classes, a third the size)."""
    head = [line for line in lines if line.startswith("#")]
    rows = [line for line in lines if not line.startswith("#")]
    return "\n".join([*head, rows[0], *rows[1::3]]) + "\n"


BASES = _bases()


@pytest.mark.parametrize("kind", sorted(BASES))
def test_the_unmutated_file_loads(kind: str, tmp_path: Path) -> None:
    """The fuzzing starts from files that load: the mutations are what is refused."""
    text, suffix, load = BASES[kind]
    path = tmp_path / f"input{suffix}"
    path.write_text(text)
    load(path)


@pytest.mark.parametrize("kind", sorted(BASES))
def test_mutated_inputs_load_or_are_one_line_errors(kind: str, tmp_path_factory: Any) -> None:
    text, suffix, load = BASES[kind]
    tmp = tmp_path_factory.mktemp(f"fuzz-{kind}")

    @settings(
        max_examples=CASES,
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(st.data())
    def case(data: st.DataObject) -> None:
        _fuzz(text, suffix, load, tmp, data)

    case()
