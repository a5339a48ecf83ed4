"""The shared channel against ns-3 (benchmarks/ns3_contention.py): the model's side and
the table always; ns-3's side, on two small cases, only where ns-3's Python bindings
are installed (pip install ns3; make ns3-validation installs them)."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import pytest

from tests.scripts import load_script

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "ns3_contention.py"
NO_NS3 = "ns-3's Python bindings are not installed (pip install ns3): no ns-3 comparison"


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    return load_script(SCRIPT, "mrcomm_bench_ns3_contention")


def test_the_model_side_loses_more_as_senders_crowd_the_air(bench: ModuleType) -> None:
    profile = bench.contention_profile()
    delivery = []
    for senders in (2, 10):
        setup = bench.setup("saturated", senders, profile, seed=1)
        outcome = bench.run_model(setup, profile, min(setup.starts) + 1.0, seed=1)
        delivery.append(outcome.delivery)
    assert 0.88 < delivery[0] < 0.98 and 0.6 < delivery[1] < 0.75
    poses = bench.setup("poses", 10, profile, seed=1)
    light = bench.run_model(poses, profile, min(poses.starts) + 2.0, seed=1)
    assert light.delivery == 1.0 and 1.9 < light.delay_ms < 2.5


def test_hidden_senders_do_not_defer_to_each_other(bench: ModuleType) -> None:
    profile = bench.contention_profile()
    setup = bench.setup("hidden", 2, profile, seed=1)
    outcome = bench.run_model(setup, profile, min(setup.starts) + 1.0, seed=1)
    assert outcome.delivery < 0.3  # in range of each other, two senders lose ~6 %


def test_ns3_agrees_on_saturated_and_hidden_senders(bench: ModuleType) -> None:
    pytest.importorskip("ns", reason=NO_NS3, exc_type=ImportError)
    with bench._filtered_stderr():
        from ns import ns  # type: ignore[import-not-found,unused-ignore]

        ns.cppyy.cppdef(bench._CPP)
    profile = bench.contention_profile()
    for case in ("saturated", "hidden"):
        setup = bench.setup(case, 5, profile, seed=1)
        stop = min(setup.starts) + 2.0
        with bench._filtered_stderr():
            theirs = bench.run_ns3(ns, setup, profile, stop, seed=1)
        ours = bench.run_model(setup, profile, stop, seed=1)
        assert ours.delivery == pytest.approx(theirs.delivery, abs=0.05), case
