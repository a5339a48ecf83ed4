"""benchmarks/bench_scale.py's tables: a configuration's name, and a saved output read
back for ``--replot`` (the figure of the radio's cost is drawn from one)."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import pytest

from tests.scripts import load_script

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_scale.py"


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    return load_script(SCRIPT, "mrcomm_bench_scale")


def test_a_configuration_is_named_by_its_options_flattened(bench: ModuleType) -> None:
    assert bench.label_of({}) == "NB · WLAN · SPL 25"
    assert bench.label_of({"network": "radio"}) == "network=radio"
    shared = {"network": "radio", "params": {"network": {"channel": "shared"}}}
    assert bench.label_of(shared) == "network=radio params.network.channel=shared"


def test_a_saved_output_gives_back_each_configurations_costs_in_order(
    bench: ModuleType, tmp_path: Path
) -> None:
    saved = tmp_path / "out.txt"
    saved.write_text(
        "Python 3.11.7, 2 CPUs, pinned to core 1; ...\n"
        "| scenario | robots | configuration | simulated s | real-time factor | wall s | CPU s "
        "| ms per step | per step, against the first | peak MB |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n"
        "| s1 | 3 | WLAN | 178.9 | 400x | 0.45 | 0.45 | 0.25 | 1.00 | 145 |\n"
        "| s1 | 3 | network=radio | 178.9 | 122x | 1.47 | 1.40 | 0.78 | 3.15 | 205 |\n"
        "| s4 | 100 | WLAN | 474.3 | 14.5x | 32.73 | 32.60 | 6.87 | 1.00 | 347 |\n"
        "| s4 | 100 | network=radio | 530.9 | 2.17x | 244.43 | 236.98 | 44.64 | 6.49 | 373 |\n"
        "WLAN: cost per step ~ N^0.93 (log-log least squares)\n"
    )
    assert bench.read_table(saved) == [
        ("WLAN", [(3, 0.25), (100, 6.87)]),
        ("network=radio", [(3, 0.78), (100, 44.64)]),
    ]
    empty = tmp_path / "empty.txt"
    empty.write_text("no table here\n")
    with pytest.raises(SystemExit, match="no table"):
        bench.read_table(empty)


def test_the_bundled_output_of_the_radio_cost_reads_back(bench: ModuleType) -> None:
    saved = SCRIPT.parent / "results" / "scale_radio.txt"
    series = dict(bench.read_table(saved))
    assert list(series) == [
        "NB · WLAN · SPL 25",
        "network=radio",
        "network=radio params.network.channel=shared",
    ]
    assert all([n for n, _ in points] == [3, 10, 30, 100] for points in series.values())
