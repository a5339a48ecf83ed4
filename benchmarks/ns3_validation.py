"""MRComm's radio model against ns-3 (issue 17 §4): the delivery ratio of a 150-byte
message over one link, vs distance, through 0-3 walls, as
:func:`mrcomm.net.radio.model.delivery_ratio` computes it and as ns-3 (the pip package
``ns3``, 3.44) simulates it in the same geometry. A benchmark, not a dependency:

    pip install ns3            # into the project venv
    python benchmarks/ns3_validation.py [--profile NAME] [--packets N] [--out DIR]

(``make ns3-validation`` does both.) Writes ``ns3_validation.csv`` and
``ns3_validation.png`` (or ``--figure PATH``) into ``--out`` and prints markdown: per
ns-3 configuration and wall count the distance where delivery falls to 0.5 in the model
and in ns-3 and the largest absolute difference of the two curves; per configuration
the equivalent hard threshold of each (the received power, dBm, at which a link
shadowed with the profile's σ would be cut off to give the same curve).

ns-3, per configuration and wall count, is one simulation (built in C++, see ``_CPP``):
one sender and one receiver per distance; receivers only listen, so they do not
interfere with each other, and each draws its own shadowing:

* 802.11g, ``AdhocWifiMac``, ``ConstantRateWifiManager`` (data = control mode); UDP
  broadcast (``UdpClient`` to 255.255.255.255, a ``UdpServer`` per receiver counts
  what arrives): no RTS/CTS, no ACK, no retransmission, each packet one attempt as in
  the model; 150 bytes of UDP payload, 214 bytes on the air with UDP, IP, LLC/SNAP and
  MAC headers and FCS (the model: 150 + 60 header bytes);
* ``YansWifiChannel``: ``LogDistancePropagationLossModel`` (the profile's exponent and
  reference loss at 1 m; the walls added to its ReferenceLoss, walls × wall loss: a
  fixed loss like the model's) chained with a ``RandomPropagationLossModel`` drawing a
  ``NormalRandomVariable`` loss per packet and receiver of variance σ², σ =
  √(shadowing² + asymmetry²), the σ ``delivery_ratio`` averages over (i.i.d. per packet
  in ns-3, so the share received estimates that average);
* ``YansWifiPhy``: TxPowerStart/End = the profile's tx power, RxSensitivity = its
  sensitivity, RxNoiseFigure such that ns-3's thermal noise kT·B·NF over 20 MHz is its
  noise floor (the noise ns-3 reports with the received frames is printed);
* preamble detection: ``ThresholdPreambleDetectionModel`` with MinimumRssi = the
  sensitivity (ns-3's default is -82 dBm) and its default 4 dB SNR threshold; for
  contrast, also none at all and ns-3's default;
* error models: ``NistErrorRateModel`` at DsssRate1Mbps (the profile's 1 Mbit/s) and at
  ErpOfdmRate6Mbps (the slowest OFDM rate), ``TableBasedErrorRateModel`` at
  ErpOfdmRate6Mbps.

Seeds: ``RngSeedManager.SetSeed(--seed)``, one run number per simulation.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import math
import os
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.special import ndtr

from mrcomm.errors import InputError
from mrcomm.net.radio.model import (
    POSE_BYTES,
    bit_error_rate,
    delivery_ratio,
    mean_power_dbm,
    packet_error_rate,
)
from mrcomm.net.radio.profile import DEFAULT_PROFILE, RadioProfile, load_profile

INSTALL_HINT = "ns-3's Python bindings are not installed: pip install ns3 (or: make ns3-validation)"
WALLS = (0, 1, 2, 3)
#: Farthest distance simulated by default, m; samples at 1 m, then every ``STEP_M``.
MAX_DISTANCE_M = 80.0
STEP_M = 2.5
#: Time between two packets of the sender, s: longer than a 214-byte frame at 1 Mbit/s
#: (~1.9 ms with its preamble) plus DIFS and the largest first backoff, so the MAC queue
#: never grows and every packet goes out once.
PACKET_INTERVAL_S = 0.005
#: Bytes ns-3 adds to the UDP payload on the air: UDP 8, IPv4 20, LLC/SNAP 8, MAC 24, FCS 4.
NS3_OVERHEAD_BYTES = 64
#: Distances (m) of the sample rows printed under the table.
SAMPLE_DISTANCES = (5.0, 20.0, 40.0, 60.0, 80.0)
#: Boltzmann constant (J/K) and the reference temperature ns-3 uses for thermal noise.
BOLTZMANN = 1.380649e-23
NOISE_TEMPERATURE_K = 290.0
#: Bandwidth over which ns-3 integrates the thermal noise for 802.11g (DSSS and
#: ERP-OFDM alike; checked with the noise ns-3 reports), Hz.
NOISE_BANDWIDTH_HZ = 20e6


def distances(max_distance: float = MAX_DISTANCE_M, step: float = STEP_M) -> list[float]:
    """Sample distances, m: 1 m, then every ``step`` up to ``max_distance``."""
    grid = np.arange(step, max_distance + 1e-9, step)
    return [float(d) for d in np.unique(np.r_[1.0, grid])]


@dataclass(frozen=True)
class Ns3Config:
    """One ns-3 set-up to compare with the model: a constant rate, an error model and
    a preamble detection (``sensitivity``: threshold model, MinimumRssi = the profile's
    sensitivity; ``none``: disabled; ``ns3-default``: ns-3's own)."""

    key: str
    label: str
    mode: str
    error_model: str
    preamble: str = "sensitivity"


CONFIGS = (
    Ns3Config("dsss1-nist", "DSSS 1 Mbit/s, Nist", "DsssRate1Mbps", "Nist"),
    Ns3Config("ofdm6-nist", "ERP-OFDM 6 Mbit/s, Nist", "ErpOfdmRate6Mbps", "Nist"),
    Ns3Config("ofdm6-table", "ERP-OFDM 6 Mbit/s, TableBased", "ErpOfdmRate6Mbps", "Table"),
    Ns3Config(
        "dsss1-nist-nopd",
        "DSSS 1 Mbit/s, Nist, no preamble detection",
        "DsssRate1Mbps",
        "Nist",
        "none",
    ),
    Ns3Config(
        "ofdm6-nist-nopd",
        "ERP-OFDM 6 Mbit/s, Nist, no preamble detection",
        "ErpOfdmRate6Mbps",
        "Nist",
        "none",
    ),
    Ns3Config(
        "dsss1-nist-pd82",
        "DSSS 1 Mbit/s, Nist, ns-3 default preamble detection",
        "DsssRate1Mbps",
        "Nist",
        "ns3-default",
    ),
)
ERROR_MODELS = {"Nist": "ns3::NistErrorRateModel", "Table": "ns3::TableBasedErrorRateModel"}
PREAMBLE = {"sensitivity": 0, "ns3-default": 1, "none": 2}

#: The simulation itself, in C++ (compiled by cppyy when the script loads ns-3): one
#: sender, one receiver per distance, UDP broadcast; returns the packets each receiver's
#: UdpServer counted and the mean noise ns-3 reported with the frames (MonitorSnifferRx).
#: Only numbers and strings cross into Python: Python proxies of ns-3 objects (nodes,
#: helpers, containers) made the ns-3 3.44 wheel crash at random (heap corruption) once
#: a simulation had some 20 nodes built from Python.
_CPP = r"""
#include "ns3/applications-module.h"
#include "ns3/core-module.h"
#include "ns3/internet-module.h"
#include "ns3/mobility-module.h"
#include "ns3/network-module.h"
#include "ns3/propagation-module.h"
#include "ns3/wifi-module.h"
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace mrcomm_ns3 {
static double g_noise_sum = 0.0;
static long g_frames = 0;

static std::string g_modes;  // the modes of the frames received, comma-separated

static void Sniff(ns3::Ptr<const ns3::Packet>, uint16_t, ns3::WifiTxVector txVector,
                  ns3::MpduInfo, ns3::SignalNoiseDbm signalNoise, uint16_t) {
  g_noise_sum += signalNoise.noise;
  ++g_frames;
  const std::string mode = txVector.GetMode().GetUniqueName();
  if (("," + g_modes + ",").find("," + mode + ",") == std::string::npos) {
    g_modes += g_modes.empty() ? mode : "," + mode;
  }
}

// The modes of the frames received in the last Run (a check that broadcasts went out
// at the configured rate: ns-3 sends group-addressed frames at NonUnicastMode).
std::string ReceivedModes() { return g_modes; }

// preamble: 0 = ThresholdPreambleDetectionModel with MinimumRssi = sensitivity,
// 1 = ns-3's default preamble detection, 2 = none (DisablePreambleDetectionModel).
std::vector<double> Run(const std::string& mode, const std::string& errorModel, int preamble,
                        double txPowerDbm, double referenceLossDb, double exponent,
                        double sigmaDb, double sensitivityDbm, double noiseFigureDb,
                        const std::vector<double>& distances, uint32_t packets,
                        uint32_t payloadBytes, double intervalS, uint32_t seed, uint64_t run) {
  using namespace ns3;
  RngSeedManager::SetSeed(seed);
  RngSeedManager::SetRun(run);
  g_noise_sum = 0.0;
  g_frames = 0;
  g_modes.clear();
  std::vector<double> out;
  {
    NodeContainer nodes;
    nodes.Create(1 + distances.size());
    WifiHelper wifi;
    wifi.SetStandard(WIFI_STANDARD_80211g);
    // Broadcasts go out at NonUnicastMode (by default the lowest basic rate, DSSS
    // 1 Mbit/s in 802.11g), not at DataMode: all three set to the chosen rate.
    wifi.SetRemoteStationManager("ns3::ConstantRateWifiManager", "DataMode", StringValue(mode),
                                 "ControlMode", StringValue(mode),
                                 "NonUnicastMode", StringValue(mode));
    YansWifiChannelHelper channel;
    channel.SetPropagationDelay("ns3::ConstantSpeedPropagationDelayModel");
    channel.AddPropagationLoss("ns3::LogDistancePropagationLossModel",
                               "Exponent", DoubleValue(exponent),
                               "ReferenceDistance", DoubleValue(1.0),
                               "ReferenceLoss", DoubleValue(referenceLossDb));
    if (sigmaDb > 0) {
      std::ostringstream variable;
      variable.precision(17);
      variable << "ns3::NormalRandomVariable[Mean=0.0|Variance=" << sigmaDb * sigmaDb << "]";
      channel.AddPropagationLoss("ns3::RandomPropagationLossModel",
                                 "Variable", StringValue(variable.str()));
    }
    YansWifiPhyHelper phy;
    phy.SetChannel(channel.Create());
    phy.Set("TxPowerStart", DoubleValue(txPowerDbm));
    phy.Set("TxPowerEnd", DoubleValue(txPowerDbm));
    phy.Set("RxSensitivity", DoubleValue(sensitivityDbm));
    phy.Set("RxNoiseFigure", DoubleValue(noiseFigureDb));
    phy.SetErrorRateModel(errorModel);
    if (preamble == 0) {
      phy.SetPreambleDetectionModel("ns3::ThresholdPreambleDetectionModel",
                                    "MinimumRssi", DoubleValue(sensitivityDbm));
    } else if (preamble == 2) {
      phy.DisablePreambleDetectionModel();
    }
    WifiMacHelper mac;
    mac.SetType("ns3::AdhocWifiMac");
    NetDeviceContainer devices = wifi.Install(phy, mac, nodes);

    Ptr<ListPositionAllocator> positions = CreateObject<ListPositionAllocator>();
    positions->Add(Vector(0.0, 0.0, 0.0));
    for (double d : distances) positions->Add(Vector(d, 0.0, 0.0));
    MobilityHelper mobility;
    mobility.SetPositionAllocator(positions);
    mobility.SetMobilityModel("ns3::ConstantPositionMobilityModel");
    mobility.Install(nodes);

    InternetStackHelper internet;
    internet.SetIpv6StackInstall(false);
    internet.Install(nodes);
    Ipv4AddressHelper address;
    address.SetBase("10.1.0.0", "255.255.0.0");
    address.Assign(devices);

    NodeContainer receivers;
    for (uint32_t i = 1; i < nodes.GetN(); ++i) {
      receivers.Add(nodes.Get(i));
      DynamicCast<WifiNetDevice>(devices.Get(i))->GetPhy()->TraceConnectWithoutContext(
          "MonitorSnifferRx", MakeCallback(&Sniff));
    }
    UdpServerHelper serverHelper(9);
    ApplicationContainer servers = serverHelper.Install(receivers);
    servers.Start(Seconds(0.0));
    UdpClientHelper client(InetSocketAddress(Ipv4Address("255.255.255.255"), 9));
    client.SetAttribute("MaxPackets", UintegerValue(packets));
    client.SetAttribute("Interval", TimeValue(Seconds(intervalS)));
    client.SetAttribute("PacketSize", UintegerValue(payloadBytes));
    const double start = 0.1;
    client.Install(nodes.Get(0)).Start(Seconds(start));

    Simulator::Stop(Seconds(start + packets * intervalS + 0.5));
    Simulator::Run();
    for (uint32_t i = 0; i < servers.GetN(); ++i) {
      out.push_back(static_cast<double>(DynamicCast<UdpServer>(servers.Get(i))->GetReceived()));
    }
    Simulator::Destroy();
  }
  out.push_back(g_frames > 0 ? g_noise_sum / g_frames : std::nan(""));
  return out;
}

// Success probability of a chunk of nbits at one SNR (linear) by an ns-3 error model.
double ChunkSuccess(const std::string& errorModel, const std::string& mode, double snr,
                    uint64_t nbits) {
  using namespace ns3;
  ObjectFactory factory;
  factory.SetTypeId(errorModel);
  Ptr<ErrorRateModel> model = factory.Create<ErrorRateModel>();
  WifiMode wifiMode(mode);
  WifiTxVector txVector;
  txVector.SetMode(wifiMode);
  txVector.SetChannelWidth(wifiMode.GetModulationClass() == WIFI_MOD_CLASS_DSSS ? 22 : 20);
  return model->GetChunkSuccessRate(wifiMode, txVector, snr, nbits);
}
}  // namespace mrcomm_ns3
"""


@contextlib.contextmanager
def _filtered_stderr() -> Iterator[None]:
    """Hide cling's harmless "Failed to materialize symbols" lines (written by C++ to
    file descriptor 2 while ns-3 loads), pass on everything else."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as capture:
        os.dup2(capture.fileno(), 2)
        try:
            yield
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            capture.seek(0)
            for line in capture.read().decode(errors="replace").splitlines():
                if "materialize symbols" not in line:
                    print(line, file=sys.stderr)


def load_ns3() -> Any:
    """ns-3's bindings (``from ns import ns``: the C++ namespace ns3 through cppyy) with
    this script's C++ part compiled in, or None when they are not installed."""
    try:
        with _filtered_stderr():
            from ns import ns  # type: ignore[import-not-found,unused-ignore]

            ns.cppyy.cppdef(_CPP)
    except (ImportError, SystemExit):  # the ``ns`` stub exits when ns3.ns is missing
        return None
    return ns


def noise_figure_db(profile: RadioProfile) -> float:
    """The receiver noise figure that makes ns-3's thermal noise the profile's floor."""
    thermal_dbm = 10.0 * math.log10(BOLTZMANN * NOISE_TEMPERATURE_K * NOISE_BANDWIDTH_HZ * 1e3)
    return profile.noise_floor_dbm - thermal_dbm


def shadowing_sigma_db(profile: RadioProfile) -> float:
    """The σ of the model's average: shadowing and per-direction offset together."""
    return math.hypot(profile.shadowing_sigma_db, profile.asymmetry_db)


@dataclass(frozen=True)
class Ns3Result:
    received: list[int]
    sent: int
    noise_dbm: float


def simulate(
    ns: Any,
    profile: RadioProfile,
    config: Ns3Config,
    walls: int,
    distances: Sequence[float],
    packets: int,
    seed: int = 1,
    run: int = 1,
) -> Ns3Result:
    """One ns-3 simulation: a sender broadcasting ``packets`` packets of 150 bytes and
    one receiver at each distance; how many each received (see the module docstring)."""
    out = list(
        ns.cppyy.gbl.mrcomm_ns3.Run(
            config.mode,
            ERROR_MODELS[config.error_model],
            PREAMBLE[config.preamble],
            profile.tx_power_dbm,
            profile.reference_loss_db + walls * profile.wall_loss_db,
            profile.exponent,
            shadowing_sigma_db(profile),
            profile.sensitivity_dbm,
            noise_figure_db(profile),
            ns.cppyy.gbl.std.vector["double"]([float(d) for d in distances]),
            packets,
            POSE_BYTES,
            PACKET_INTERVAL_S,
            seed,
            run,
        )
    )
    modes = str(ns.cppyy.gbl.mrcomm_ns3.ReceivedModes())
    if modes not in ("", config.mode):
        raise RuntimeError(f"ns-3 sent the {config.key} broadcasts at {modes}, not {config.mode}")
    return Ns3Result([int(x) for x in out[:-1]], packets, float(out[-1]))


def frame_bits() -> int:
    """Bits of one ns-3 frame: payload + UDP, IP, LLC/SNAP and MAC headers + FCS."""
    return (POSE_BYTES + NS3_OVERHEAD_BYTES) * 8


def ns3_snr50_db(ns: Any, config: Ns3Config, bits: int) -> float:
    """The SNR (dB) at which ns-3's error model loses half of the frames of ``bits``."""
    lo, hi = -20.0, 30.0
    success = ns.cppyy.gbl.mrcomm_ns3.ChunkSuccess
    error_model = ERROR_MODELS[config.error_model]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if success(error_model, config.mode, 10.0 ** (mid / 10.0), bits) < 0.5:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def model_snr50_db(profile: RadioProfile) -> float:
    """The SNR (dB) at which the model's PER reaches 0.5 for a pose message."""
    bits = (POSE_BYTES + profile.header_bytes) * 8
    lo, hi = -20.0, 30.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        ber = bit_error_rate(profile, profile.noise_floor_dbm + mid)
        if float(packet_error_rate(ber, bits)) > 0.5:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def equivalent_threshold_dbm(
    power_dbm: Sequence[float], delivered: Sequence[float], trials: Sequence[float], sigma: float
) -> float:
    """The hard threshold T (dBm) whose shadowed delivery Φ((P − T)/σ) fits the points
    best (binomial maximum likelihood): one number for where a curve cuts off."""
    p = np.asarray(power_dbm, dtype=np.float64)
    k = np.asarray(delivered, dtype=np.float64)
    n = np.asarray(trials, dtype=np.float64)

    def nll(t: float) -> float:
        q = np.clip(ndtr((p - t) / sigma), 1e-12, 1 - 1e-12)
        return float(-(k * np.log(q) + (n - k) * np.log1p(-q)).sum())

    fit = minimize_scalar(nll, bounds=(-140.0, 0.0), method="bounded", options={"xatol": 1e-4})
    return float(fit.x)


def d50(distance: Sequence[float], delivery: Sequence[float]) -> float:
    """Where a curve first falls below 0.5, m (linear interpolation between samples;
    NaN if it never does, the first distance if it starts below)."""
    d = np.asarray(distance, dtype=np.float64)
    y = np.asarray(delivery, dtype=np.float64)
    below = np.flatnonzero(y < 0.5)
    if below.size == 0:
        return math.nan
    k = int(below[0])
    if k == 0:
        return float(d[0])
    return float(d[k - 1] + (y[k - 1] - 0.5) / (y[k - 1] - y[k]) * (d[k] - d[k - 1]))


def model_d50(profile: RadioProfile, walls: int, max_distance: float) -> float:
    """The model's d50 on a 1 cm grid (NaN beyond ``max_distance``)."""
    grid = np.arange(1.0, max_distance + 1e-9, 0.01)
    return d50(grid.tolist(), delivery_ratio(profile, grid, walls).tolist())


@dataclass(frozen=True)
class Row:
    """One point: a configuration, a wall count, a distance; model and ns-3."""

    config: str
    walls: int
    distance_m: float
    mean_power_dbm: float
    model: float
    received: int
    sent: int

    @property
    def ns3(self) -> float:
        return self.received / self.sent


@dataclass(frozen=True)
class Comparison:
    rows: list[Row]
    noise_dbm: dict[str, float]  # mean noise ns-3 reported, per configuration


def compare(
    ns: Any,
    profile: RadioProfile,
    configs: Sequence[Ns3Config] = CONFIGS,
    walls: Sequence[int] = WALLS,
    points: Sequence[float] | None = None,
    packets: int = 1000,
    seed: int = 1,
    log: bool = False,
) -> Comparison:
    """Model and ns-3 at every (configuration, walls, distance)."""
    points = distances() if points is None else list(points)
    rows: list[Row] = []
    noise: dict[str, float] = {}
    run = 0
    for config in configs:
        noises = []
        for w in walls:
            run += 1
            started = time.perf_counter()
            result = simulate(ns, profile, config, w, points, packets, seed=seed, run=run)
            if log:
                took = time.perf_counter() - started
                print(f"  ns-3 {config.key}, {w} walls: {took:.1f} s", file=sys.stderr)
            if not math.isnan(result.noise_dbm):
                noises.append(result.noise_dbm)
            model = delivery_ratio(profile, points, w)
            power = mean_power_dbm(profile, points, w)
            rows += [
                Row(config.key, w, d, float(power[k]), float(model[k]), result.received[k], packets)
                for k, d in enumerate(points)
            ]
        noise[config.key] = float(np.mean(noises)) if noises else math.nan
    return Comparison(rows, noise)


def config_by_key(key: str) -> Ns3Config:
    return next(c for c in CONFIGS if c.key == key)


def write_csv(rows: Sequence[Row], profile: RadioProfile, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        out = csv.writer(f)
        out.writerow(
            [
                "profile",
                "ns3_config",
                "rate",
                "error_model",
                "preamble_detection",
                "walls",
                "distance_m",
                "mean_power_dbm",
                "model_delivery",
                "ns3_received",
                "ns3_sent",
                "ns3_delivery",
                "ns3_stderr",
            ]
        )
        for r in rows:
            c = config_by_key(r.config)
            stderr = math.sqrt(r.ns3 * (1.0 - r.ns3) / r.sent)
            out.writerow(
                [
                    profile.name,
                    r.config,
                    c.mode,
                    c.error_model,
                    c.preamble,
                    r.walls,
                    f"{r.distance_m:g}",
                    f"{r.mean_power_dbm:.2f}",
                    f"{r.model:.4f}",
                    r.received,
                    r.sent,
                    f"{r.ns3:.4f}",
                    f"{stderr:.4f}",
                ]
            )


def series(rows: Sequence[Row], config: str, walls: int) -> list[Row]:
    """One curve's points, by distance."""
    chosen = (r for r in rows if r.config == config and r.walls == walls)
    return sorted(chosen, key=lambda r: r.distance_m)


@dataclass(frozen=True)
class Summary:
    config: Ns3Config
    walls: int
    d50_model: float
    d50_ns3: float
    max_diff: float
    max_diff_at: float
    max_distance: float


def summary(rows: Sequence[Row], profile: RadioProfile) -> list[Summary]:
    """Per configuration and wall count: d50 of the model and of ns-3, the largest
    absolute difference of the curves and where."""
    out = []
    for config in CONFIGS:
        for w in sorted({r.walls for r in rows if r.config == config.key}):
            points = series(rows, config.key, w)
            d = [r.distance_m for r in points]
            diff = [abs(r.ns3 - r.model) for r in points]
            k = int(np.argmax(diff))
            out.append(
                Summary(
                    config,
                    w,
                    model_d50(profile, w, max(d)),
                    d50(d, [r.ns3 for r in points]),
                    diff[k],
                    d[k],
                    max(d),
                )
            )
    return out


def thresholds(rows: Sequence[Row], profile: RadioProfile) -> dict[str, tuple[float, float]]:
    """Per configuration: the equivalent hard threshold (dBm) of the model and of ns-3,
    fitted over all its points (the model's expected share as if it were counted)."""
    sigma = shadowing_sigma_db(profile)
    out = {}
    for key in dict.fromkeys(r.config for r in rows):
        mine = [r for r in rows if r.config == key]
        power = [r.mean_power_dbm for r in mine]
        sent = [r.sent for r in mine]
        out[key] = (
            equivalent_threshold_dbm(power, [r.model * r.sent for r in mine], sent, sigma),
            equivalent_threshold_dbm(power, [r.received for r in mine], sent, sigma),
        )
    return out


def _metres(value: float, limit: float) -> str:
    return f"> {limit:g}" if math.isnan(value) else f"{value:.1f}"


def markdown(
    comparison: Comparison, profile: RadioProfile, snr50: dict[str, float] | None = None
) -> str:
    """The results as markdown: the d50 table, the thresholds, sample rows."""
    rows = comparison.rows
    keys = list(dict.fromkeys(r.config for r in rows))
    configs = [config_by_key(k) for k in keys]
    noise = ", ".join(f"{v:.2f}" for v in comparison.noise_dbm.values())
    lines = [
        f"Profile {profile.name}: {profile.tx_power_dbm:g} dBm, L0 "
        f"{profile.reference_loss_db:g} dB, n {profile.exponent:g}, {profile.wall_loss_db:g} "
        f"dB per wall, σ {shadowing_sigma_db(profile):.2f} dB (shadowing and asymmetry), "
        f"sensitivity {profile.sensitivity_dbm:g} dBm, noise floor {profile.noise_floor_dbm:g} "
        f"dBm (ns-3: noise figure {noise_figure_db(profile):.2f} dB; noise reported with the "
        f"received frames {noise} dBm); {POSE_BYTES}-byte messages; {rows[0].sent} packets "
        "per ns-3 point."
        + (
            f" Note: the profile has {profile.fading} fading, which the model's curve "
            "includes and the ns-3 side does not."
            if profile.fading != "none"
            else ""
        ),
        "",
        "| ns-3 configuration | walls | d50 model (m) | d50 ns-3 (m) | ns-3 − model (m) "
        "| max abs. difference (at m) |",
        "|---|---|---|---|---|---|",
    ]
    for s in summary(rows, profile):
        delta = s.d50_ns3 - s.d50_model
        delta_text = "–" if math.isnan(delta) else f"{delta:+.1f}"
        lines.append(
            f"| {s.config.label} | {s.walls} | {_metres(s.d50_model, s.max_distance)} | "
            f"{_metres(s.d50_ns3, s.max_distance)} | {delta_text} | "
            f"{s.max_diff:.3f} ({s.max_diff_at:g}) |"
        )
    lines += [
        "",
        "Equivalent hard threshold (the received power below which a link would be cut "
        "off, fitted to all 4 wall counts with the shadowing σ) and the SNR at which the "
        "packet error rate without shadowing is 0.5:",
        "",
        "| ns-3 configuration | model threshold (dBm) | ns-3 threshold (dBm) | ns-3 − model "
        "(dB) | PER 0.5 at SNR: model / ns-3 error model (dB) |",
        "|---|---|---|---|---|",
    ]
    model_snr = model_snr50_db(profile)
    for key, (t_model, t_ns3) in thresholds(rows, profile).items():
        snr_text = f"{model_snr:.1f} / " + (f"{snr50[key]:.1f}" if snr50 and key in snr50 else "–")
        lines.append(
            f"| {config_by_key(key).label} | {t_model:.1f} | {t_ns3:.1f} | "
            f"{t_ns3 - t_model:+.1f} | {snr_text} |"
        )
    lines += [
        "",
        "Sample rows (delivery ratio):",
        "",
        "| walls | distance (m) | mean power (dBm) | model | "
        + " | ".join(f"ns-3 {k}" for k in keys)
        + " |",
        "|---|---|---|---|" + "---|" * len(keys),
    ]
    for w in sorted({r.walls for r in rows}):
        for d in SAMPLE_DISTANCES:
            at = {r.config: r for r in rows if r.walls == w and r.distance_m == d}
            if not at:
                continue
            first = next(iter(at.values()))
            lines.append(
                f"| {w} | {d:g} | {first.mean_power_dbm:.1f} | {first.model:.3f} | "
                + " | ".join(f"{at[c.key].ns3:.3f}" if c.key in at else "–" for c in configs)
                + " |"
            )
    return "\n".join(lines)


#: The panel that also shows the model with ns-3's reception rule.
RULE_PANEL = "dsss1-nist"


def read_csv(path: Path) -> list[Row]:
    """The rows of a CSV :func:`write_csv` wrote."""
    with path.open() as f:
        return [
            Row(r["ns3_config"], int(r["walls"]), float(r["distance_m"]),
                float(r["mean_power_dbm"]), float(r["model_delivery"]),
                int(r["ns3_received"]), int(r["ns3_sent"]))
            for r in csv.DictReader(f)
        ]  # fmt: skip


def plot(rows: Sequence[Row], profile: RadioProfile, path: Path) -> None:
    """One panel per ns-3 configuration: the model solid, ns-3 markers, a colour per
    wall count; on the DSSS panel with ns-3's preamble threshold, dashed, the model
    with ns-3's reception rule (``modulation: dsss``, ``preamble_snr_db: 4``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = list(dict.fromkeys(r.config for r in rows))
    walls = sorted({r.walls for r in rows})
    max_d = max(r.distance_m for r in rows)
    grid = np.linspace(1.0, max_d, 400)
    model = {w: delivery_ratio(profile, grid, w) for w in walls}
    ns3_rule = profile.model_copy(update={"modulation": "dsss", "preamble_snr_db": 4.0})
    with_rule = {w: delivery_ratio(ns3_rule, grid, w) for w in walls}
    markers = "osD^v<>"
    columns = min(3, len(keys))
    lines = math.ceil(len(keys) / columns)
    fig, axes = plt.subplots(
        lines,
        columns,
        figsize=(4.3 * columns, 3.6 * lines),
        sharex=True,
        sharey=True,
        squeeze=False,
    )
    for ax, key in zip(axes.flat, keys, strict=False):
        for i, w in enumerate(walls):
            label = f"{w} wall{'' if w == 1 else 's'}"
            ax.plot(grid, model[w], "-", color=f"C{i}", lw=1.5, label=f"model, {label}")
            if key == RULE_PANEL:
                ax.plot(grid, with_rule[w], "--", color=f"C{i}", lw=1.0,
                        label=f"model, ns-3's rule, {label}")  # fmt: skip
            points = series(rows, key, w)
            ax.plot(
                [r.distance_m for r in points],
                [r.ns3 for r in points],
                markers[i % len(markers)],
                color=f"C{i}",
                ms=3.5,
                mfc="none",
                mew=0.9,
                label=f"ns-3, {label}",
            )
        ax.set_title(config_by_key(key).label, fontsize=9)
        ax.set_xlim(0, max_d)
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(keys) :]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("distance (m)")
    for ax in axes[:, 0]:
        ax.set_ylabel(f"delivery ratio ({POSE_BYTES}-byte message)")
    axes.flat[0].legend(fontsize=6, loc="lower left", ncol=2)
    fig.suptitle(
        f"MRComm radio model ({profile.name}, solid) vs ns-3 3.44 (markers, "
        f"{rows[0].sent} packets per point)",
        fontsize=10,
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=300)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="MRComm's radio model vs ns-3 (issue 17 §4)")
    parser.add_argument("--profile", default=DEFAULT_PROFILE, help="radio profile (name or YAML)")
    parser.add_argument("--packets", type=int, default=1000, help="packets per ns-3 point")
    parser.add_argument(
        "--out", type=Path, default=Path("benchmarks/results"), help="folder of the CSV"
    )
    parser.add_argument("--figure", type=Path, help="figure (default OUT/ns3_validation.png)")
    parser.add_argument("--seed", type=int, default=1, help="ns-3 RngSeedManager seed")
    parser.add_argument(
        "--max-distance", type=float, default=MAX_DISTANCE_M, help="farthest distance, m"
    )
    parser.add_argument(
        "--config",
        action="append",
        choices=[c.key for c in CONFIGS],
        help="an ns-3 configuration to run (repeatable; default: all)",
    )
    parser.add_argument(
        "--replot", type=Path, help="draw --figure from a CSV this script wrote (no ns-3)"
    )
    args = parser.parse_args(argv)
    if args.replot is not None:
        if args.figure is None:
            parser.error("--replot needs --figure")
        try:
            rows = read_csv(args.replot)
            if not rows:
                raise ValueError("no rows")
        except (OSError, KeyError, ValueError) as error:
            parser.error(f"--replot {args.replot}: not a CSV this script wrote ({error!r})")
        plot(rows, load_profile(args.profile), args.figure)
        return 0
    if args.packets < 1:
        parser.error("--packets must be at least 1")
    if args.max_distance < STEP_M:
        parser.error(f"--max-distance must be at least {STEP_M:g} m")
    try:
        profile = load_profile(args.profile)
    except InputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    ns = load_ns3()
    if ns is None:
        print(INSTALL_HINT, file=sys.stderr)
        return 2
    configs = [c for c in CONFIGS if args.config is None or c.key in args.config]
    load_before = os.getloadavg()
    started = time.perf_counter()
    comparison = compare(
        ns,
        profile,
        configs,
        points=distances(args.max_distance),
        packets=args.packets,
        seed=args.seed,
        log=True,
    )
    elapsed = time.perf_counter() - started
    bits = frame_bits()
    snr50 = {c.key: ns3_snr50_db(ns, c, bits) for c in configs}
    csv_path = args.out / "ns3_validation.csv"
    figure = args.figure or args.out / "ns3_validation.png"
    write_csv(comparison.rows, profile, csv_path)
    plot(comparison.rows, profile, figure)
    print(markdown(comparison, profile, snr50))
    print()
    print(
        f"ns-3 simulations: {elapsed:.1f} s wall ({len(configs) * len(WALLS)} simulations); "
        f"load average {load_before[0]:.2f} before, {os.getloadavg()[0]:.2f} after; wrote "
        f"{csv_path} and {figure}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
