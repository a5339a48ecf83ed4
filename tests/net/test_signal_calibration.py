"""Calibration CSV loading: valid files, and one-line errors naming file, line, column."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrcomm.errors import InputError
from mrcomm.net.signal.calibration import Calibration, load_calibration, write_calibration


def _rows(n: int = 12, los: str = "true") -> list[str]:
    return [f"{1 + i * 0.5},{-30 - 2 * i},{los}" for i in range(n)]


def _write(tmp_path: Path, lines: list[str], name: str = "cal.csv") -> Path:
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_loads_comments_booleans_and_extra_columns(tmp_path: Path) -> None:
    lines = ["# SYNTHETIC test data", "", "Distance, RSSI ,line_of_sight,note"]
    lines += [r + ",x" for r in _rows(12, "1")] + [r + ",y" for r in _rows(12, "No")]
    cal = load_calibration(_write(tmp_path, lines))
    assert cal.distance.size == 24
    assert cal.synthetic
    assert int(cal.line_of_sight.sum()) == 12
    d, r = cal.of_class(False)
    assert d[0] == 1.0 and r[0] == -30.0
    distances, means = cal.means(True)
    assert distances.size == 12 and means[1] == -32.0


def test_round_trip_write_load(tmp_path: Path) -> None:
    cal = Calibration(
        np.array([0.2, 1.0] * 10 + [0.5, 3.0] * 10),
        np.arange(40, dtype=float) * -1.0,
        np.array([True] * 20 + [False] * 20),
    )
    path = tmp_path / "out.csv"
    write_calibration(path, cal, ["generated for a test"])
    back = load_calibration(path)
    assert back.comments == ("generated for a test",)
    assert np.array_equal(back.distance, cal.distance)
    assert np.array_equal(back.rssi, cal.rssi)
    assert np.array_equal(back.line_of_sight, cal.line_of_sight)


@pytest.mark.parametrize(
    ("lines", "expected"),
    [
        (
            ["distance,rsi,line_of_sight", "1,-30,true"],
            "missing column 'rssi' (did you mean 'rsi'?)",
        ),
        (
            ["# only comments"],
            "no header row",
        ),
        (
            ["distance,rssi,line_of_sight", "1,-30,true", "2,abc,true"],
            "line 3, column rssi: 'abc' is not a number",
        ),
        (
            ["distance,rssi,line_of_sight", "1,-30,true", "-2,-31,true"],
            "line 3, column distance: negative distance -2",
        ),
        (
            ["distance,rssi,line_of_sight", "nan,-30,true"],
            "line 2, column distance: 'nan' is not a finite number",
        ),
        (
            ["distance,rssi,line_of_sight", "1,-30,maybe"],
            "line 2, column line_of_sight: 'maybe' is not true/false",
        ),
        (["distance,rssi,line_of_sight", "1,-30"], "line 2: 2 values, expected 3"),
    ],
)
def test_bad_rows_are_one_line_errors(tmp_path: Path, lines: list[str], expected: str) -> None:
    path = _write(tmp_path, lines)
    with pytest.raises(InputError) as err:
        load_calibration(path)
    message = err.value.one_line()
    assert message.startswith(str(path))
    assert expected in message
    assert "\n" not in message


def test_too_few_points_or_missing_class(tmp_path: Path) -> None:
    header = ["distance,rssi,line_of_sight"]
    only_los = _write(tmp_path, header + _rows(12, "true"), "a.csv")
    with pytest.raises(InputError, match="no obstructed readings"):
        load_calibration(only_los)
    few = _write(tmp_path, header + _rows(12, "true") + _rows(4, "false"), "b.csv")
    with pytest.raises(InputError, match="only 4 obstructed readings, need at least 10"):
        load_calibration(few)
    one_distance = _write(tmp_path, header + _rows(12, "true") + ["2,-40,false"] * 12, "c.csv")
    with pytest.raises(InputError, match="obstructed readings are all at one distance"):
        load_calibration(one_distance)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="file not found"):
        load_calibration(tmp_path / "nope.csv")
