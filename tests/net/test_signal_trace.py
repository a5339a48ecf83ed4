"""RSSI trace replay: zero-order hold, NaN where unknown, one-line load errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mrcomm.errors import InputError
from mrcomm.net.signal.trace import RssiTrace

TRACE = """# recorded on the office floor
time,from,to,rssi
0.0,robot_1,robot_2,-40
0.0,robot_2,robot_1,-41
0.5,robot_1,robot_2,-45
1.0,robot_1,robot_3,-60
1.0,robot_1,robot_2,-47
1.0,robot_1,robot_2,-48
"""


@pytest.fixture
def trace(tmp_path: Path) -> RssiTrace:
    path = tmp_path / "trace.csv"
    path.write_text(TRACE)
    return RssiTrace.load(path)


def test_zero_order_hold(trace: RssiTrace) -> None:
    ids = ["robot_1", "robot_2", "robot_3"]
    before = trace.matrix_at(-0.1, ids)
    assert np.isnan(before).all()
    m = trace.matrix_at(0.0, ids)  # a reading at exactly t counts
    assert m[0, 1] == -40 and m[1, 0] == -41
    assert np.isnan(m[0, 2]) and np.isnan(np.diag(m)).all()
    assert trace.matrix_at(0.49, ids)[0, 1] == -40
    assert trace.matrix_at(0.5, ids)[0, 1] == -45
    late = trace.matrix_at(100.0, ids)
    assert late[0, 1] == -48  # duplicate time: the later line wins
    assert late[0, 2] == -60 and late[1, 0] == -41
    assert np.isnan(late[2, 0]) and np.isnan(late[2, 1])


def test_order_of_ids_and_unknown_robots(trace: RssiTrace) -> None:
    m = trace.matrix_at(1.0, ["robot_2", "ghost", "robot_1"])
    assert m[0, 2] == -41 and m[2, 0] == -48
    assert np.isnan(m[1]).all() and np.isnan(m[:, 1]).all()
    assert trace.robots == ["robot_1", "robot_2", "robot_3"]


def test_matches_a_brute_force_lookup() -> None:
    rng = np.random.default_rng(5)
    ids = [f"r{i}" for i in range(5)]
    n = 400
    src = [ids[i] for i in rng.integers(0, 5, n)]
    dst = [
        ids[(ids.index(s) + 1 + int(k)) % 5]
        for s, k in zip(src, rng.integers(0, 4, n), strict=True)
    ]
    times = np.round(rng.uniform(0, 50, n), 1)
    values = rng.uniform(-80, -30, n)
    trace = RssiTrace.from_readings(times, src, dst, values)
    for t in rng.uniform(-1, 52, 40):
        got = trace.matrix_at(float(t), ids)
        for i, a in enumerate(ids):
            for j, b in enumerate(ids):
                idx = [k for k in range(n) if src[k] == a and dst[k] == b and times[k] <= t]
                if not idx:
                    assert np.isnan(got[i, j])
                else:
                    last = max(idx, key=lambda k: (times[k], k))
                    assert got[i, j] == values[last]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("time,from,rssi\n", "missing column 'to'"),
        ("time,from,to,rssi\n", "no readings"),
        (
            "time,from,to,rssi\n0,a,b,-40\nsoon,a,b,-41\n",
            "line 3, column time: 'soon' is not a number",
        ),
        ("time,from,to,rssi\n0,a,a,-40\n", "line 2, column to: reading of 'a' by itself"),
        ("time,from,to,rssi\n0,,b,-40\n", "line 2, column from: empty robot id"),
        ("time,from,to,rssi\n0,a,b,inf\n", "line 2, column rssi: 'inf' is not a finite number"),
    ],
)
def test_load_errors(tmp_path: Path, text: str, expected: str) -> None:
    path = tmp_path / "t.csv"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        RssiTrace.load(path)
    assert err.value.one_line().startswith(str(path))
    assert expected in err.value.one_line()
