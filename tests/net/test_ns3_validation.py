"""The radio model vs ns-3 benchmark (benchmarks/ns3_validation.py): its helpers and its
refusal without ns-3 always; the ns-3 comparison itself, on a handful of points with few
packets, only where ns-3's Python bindings are installed (pip install ns3; make
ns3-validation installs them)."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from scipy.special import ndtr

from mrcomm.net.radio.model import delivery_ratio
from mrcomm.net.radio.profile import load_profile
from tests.scripts import load_script

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "ns3_validation.py"
NO_NS3 = "ns-3's Python bindings are not installed (pip install ns3): no ns-3 comparison"


def _script() -> ModuleType:
    return load_script(SCRIPT, "mrcomm_bench_ns3_validation")


@pytest.fixture(scope="module")
def bench() -> ModuleType:
    return _script()


@pytest.fixture(scope="module")
def ns3(bench: ModuleType) -> Any:
    pytest.importorskip("ns", reason=NO_NS3, exc_type=ImportError)
    ns = bench.load_ns3()
    assert ns is not None, "ns imports but the benchmark could not load it"
    return ns


def test_without_ns3_exits_2_with_one_line(tmp_path: Path) -> None:
    # A module named ns that fails to import stands for a machine without ns-3.
    (tmp_path / "ns.py").write_text("raise ImportError('no ns-3 here')\n")
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "MPLBACKEND": "Agg"}
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--packets", "1", "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0
    assert "pip install ns3" in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()


def test_model_curves_fall_with_distance_and_walls() -> None:
    profile = load_profile("office-2.4ghz")
    d = np.linspace(1.0, 80.0, 100)
    curves = [delivery_ratio(profile, d, w) for w in range(4)]
    for curve in curves:
        assert np.all(np.diff(curve) <= 1e-12)
        assert curve[0] > 0.99
    for nearer, farther in itertools.pairwise(curves):
        assert np.all(farther <= nearer + 1e-12)


def test_d50_and_equivalent_threshold(bench: ModuleType) -> None:
    assert bench.d50([1, 2, 3, 4], [1.0, 0.8, 0.4, 0.1]) == pytest.approx(2.75)
    assert np.isnan(bench.d50([1, 2], [1.0, 0.9]))
    assert bench.d50([1, 2], [0.3, 0.1]) == 1
    # The fit recovers the threshold of curves built from it.
    power = np.linspace(-110.0, -70.0, 41)
    share = ndtr((power - -91.0) / 6.0)
    fitted = bench.equivalent_threshold_dbm(power, share * 1000, np.full(41, 1000), 6.0)
    assert fitted == pytest.approx(-91.0, abs=0.01)
    profile = load_profile("office-2.4ghz")
    d50s = [bench.model_d50(profile, w, 80.0) for w in range(4)]
    assert d50s == sorted(d50s, reverse=True)
    # The model loses half its pose messages about 8 dB above the noise floor.
    assert 7.0 < bench.model_snr50_db(profile) < 9.0


def test_ns3_delivers_close_by_and_loses_far_behind_walls(bench: ModuleType, ns3: Any) -> None:
    profile = load_profile("office-2.4ghz")
    config = bench.config_by_key("dsss1-nist")
    near = bench.compare(ns3, profile, [config], walls=[0], points=[2.0], packets=60)
    far = bench.compare(ns3, profile, [config], walls=[3], points=[80.0], packets=60)
    (close,) = near.rows
    (distant,) = far.rows
    assert close.sent == distant.sent == 60
    assert close.ns3 >= 0.95
    assert distant.ns3 <= 0.1
    assert close.model == pytest.approx(float(delivery_ratio(profile, [2.0], 0)[0]))
    # ns-3's receivers hear the profile's noise floor (the noise figure is right).
    assert near.noise_dbm["dsss1-nist"] == pytest.approx(profile.noise_floor_dbm, abs=0.1)


def test_ns3_broadcasts_at_the_configured_rate(bench: ModuleType, ns3: Any) -> None:
    # Without shadowing, 1.5 dB above the noise floor and without preamble detection:
    # DSSS 1 Mbit/s (13 dB of processing gain) gets every packet through, OFDM 6 Mbit/s
    # none. Were broadcasts sent at ns-3's default non-unicast rate (DSSS 1 Mbit/s),
    # both would.
    profile = load_profile("office-2.4ghz").model_copy(
        update={"shadowing_sigma_db": 0.0, "asymmetry_db": 0.0}
    )
    power = profile.noise_floor_dbm + 1.5
    distance = 10 ** (
        (profile.tx_power_dbm - profile.reference_loss_db - power) / (10.0 * profile.exponent)
    )
    shares = {}
    for key in ("dsss1-nist-nopd", "ofdm6-nist-nopd"):
        config = bench.config_by_key(key)
        result = bench.simulate(ns3, profile, config, 0, [distance], packets=40)
        shares[key] = result.received[0] / result.sent
    assert shares == {"dsss1-nist-nopd": 1.0, "ofdm6-nist-nopd": 0.0}


def test_with_ns3s_reception_rule_the_model_follows_its_recorded_curves() -> None:
    """ns-3's rule — DSSS's spread DBPSK and a 4 dB preamble threshold — in a profile
    (modulation: dsss, preamble_snr_db: 4) brings the model onto ns-3's recorded
    single-link curves (benchmarks/results/ns3_validation.csv, DSSS 1 Mbit/s, Nist,
    10,000 packets a point) within 0.03 at every distance and wall count (the goal is
    0.05; ns-3's standard error is at most 0.005), where the default QPSK rule is off by
    up to 0.26."""
    import csv

    recorded = SCRIPT.parent / "results" / "ns3_validation.csv"
    with recorded.open() as f:
        rows = [r for r in csv.DictReader(f) if r["ns3_config"] == "dsss1-nist"]
    base = load_profile("office-2.4ghz")
    dsss = base.model_copy(update={"modulation": "dsss", "preamble_snr_db": 4.0})
    for walls in range(4):
        mine = [r for r in rows if int(r["walls"]) == walls]
        distance = np.array([float(r["distance_m"]) for r in mine])
        theirs = np.array([float(r["ns3_delivery"]) for r in mine])
        assert np.abs(delivery_ratio(dsss, distance, walls) - theirs).max() < 0.03, walls
        assert np.abs(delivery_ratio(base, distance, walls) - theirs).max() > 0.2, walls
