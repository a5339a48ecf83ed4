"""The shared channel (``network.channel: shared``, :mod:`mrcomm.net.radio.medium`)
against ns-3's 802.11 with the same nodes, the same received powers and the same
traffic. A benchmark, not a dependency:

    pip install ns3            # into the project venv (make ns3-validation does it)
    python benchmarks/ns3_contention.py [--out DIR] [--figure PATH] [--seconds S] [--seeds 1 2 3]

Three cases, each for 2, 5, 10, 20 and 50 senders, for each of ``--seeds`` (each seed
its own start instants and draws on both sides; the outcomes pooled):

* ``saturated``: every sender always has a frame waiting (a packet every 0.5 ms, more
  than the channel carries), all within range of each other (on a 5 m circle);
* ``poses``: the team's real traffic, a 150-byte pose every 0.2 s per sender (5 Hz,
  each sender's first at a uniform instant of the first 0.2 s), all in range;
* ``hidden``: the senders in two groups that cannot hear each other (200 dB apart),
  saturated, and four listeners between them that hear both groups 10 dB weaker than
  a group hears itself: every frame a listener hears may meet a hidden one.

For each: the delivery ratio (frames received over frames sent times the receivers in
range; in ``hidden``, at the listeners), the throughput (bits of payload received per
second per receiver) and, for ``poses``, the mean delay from a packet's publication to
its reception. Only what ends before the last publication counts, on both sides.
Both sides broadcast (no acknowledgement, no retry) 150-byte payloads,
214 bytes on the air with UDP, IP, LLC/SNAP, MAC header and FCS, at 802.11b's DSSS
1 Mbit/s with the long preamble (192 µs): ns-3 3.44 with ``WIFI_STANDARD_80211b``,
``ConstantRateWifiManager`` at DsssRate1Mbps, ``AdhocWifiMac``, ``YansWifiPhy`` (noise
figure giving the profile's noise floor, RxSensitivity = its sensitivity, threshold
preamble detection 4 dB with MinimumRssi = the sensitivity), the received powers set
pair by pair with ``MatrixPropagationLossModel``; the model with the bundled profile's
values and ns-3's reception rule (``modulation: dsss``, ``preamble_snr_db: 4``) and
802.11b's MAC timing (the profile's defaults), the frames submitted at the same instants.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mrcomm.net.radio.medium import SharedMedium
from mrcomm.net.radio.profile import DEFAULT_PROFILE, RadioProfile, load_profile
from mrcomm.net.radio.reception import ber, per

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ns3_validation import INSTALL_HINT, _filtered_stderr, noise_figure_db

SENDERS = (2, 5, 10, 20, 50)
CASES = ("saturated", "poses", "hidden")
PAYLOAD_BYTES = 150
#: Bytes ns-3 adds to the UDP payload on the air: UDP 8, IPv4 20, LLC/SNAP 8, MAC 24, FCS 4.
OVERHEAD_BYTES = 64
SATURATED_INTERVAL_S = 0.0005
POSE_INTERVAL_S = 0.2
LISTENERS = 4
#: Loss between nodes that must not hear each other, dB.
APART_DB = 200.0
#: How much weaker a listener hears each group than the group hears itself, dB.
LISTENER_MARGIN_DB = 10.0

_CPP = r"""
#include "ns3/applications-module.h"
#include "ns3/core-module.h"
#include "ns3/internet-module.h"
#include "ns3/mobility-module.h"
#include "ns3/network-module.h"
#include "ns3/propagation-module.h"
#include "ns3/wifi-module.h"
#include <vector>

namespace mrcomm_contention {
static std::vector<double> g_tx;
static std::vector<double> g_rx;
static std::vector<double> g_delay;

static void TxBegin(uint32_t node, ns3::Ptr<const ns3::Packet>, double) { g_tx[node] += 1; }

static void Received(uint32_t node, ns3::Ptr<const ns3::Packet> packet, const ns3::Address&,
                     const ns3::Address&) {
  ns3::Ptr<ns3::Packet> copy = packet->Copy();
  ns3::SeqTsHeader header;
  copy->RemoveHeader(header);
  g_rx[node] += 1;
  g_delay[node] += (ns3::Simulator::Now() - header.GetTs()).GetSeconds();
}

// n nodes, the first `senders` of them sending; loss[a * n + b] dB from a to b.
// Returns tx frames of each node, then received packets, then the sum of their delays.
std::vector<double> Run(uint32_t n, uint32_t senders, const std::vector<double>& loss,
                        double txPowerDbm, double sensitivityDbm, double noiseFigureDb,
                        const std::vector<double>& starts, double interval, double stopS,
                        uint32_t payloadBytes, uint32_t seed, uint64_t run) {
  using namespace ns3;
  RngSeedManager::SetSeed(seed);
  RngSeedManager::SetRun(run);
  g_tx.assign(n, 0.0);
  g_rx.assign(n, 0.0);
  g_delay.assign(n, 0.0);
  {
    NodeContainer nodes;
    nodes.Create(n);
    WifiHelper wifi;
    wifi.SetStandard(WIFI_STANDARD_80211b);
    wifi.SetRemoteStationManager("ns3::ConstantRateWifiManager",
                                 "DataMode", StringValue("DsssRate1Mbps"),
                                 "ControlMode", StringValue("DsssRate1Mbps"),
                                 "NonUnicastMode", StringValue("DsssRate1Mbps"));
    Ptr<MatrixPropagationLossModel> matrix = CreateObject<MatrixPropagationLossModel>();
    matrix->SetDefaultLoss(400.0);
    MobilityHelper mobility;
    mobility.SetMobilityModel("ns3::ConstantPositionMobilityModel");
    mobility.Install(nodes);
    for (uint32_t i = 0; i < n; ++i) {
      nodes.Get(i)->GetObject<MobilityModel>()->SetPosition(Vector(i, 0, 0));
    }
    for (uint32_t a = 0; a < n; ++a) {
      for (uint32_t b = 0; b < n; ++b) {
        if (a != b) {
          matrix->SetLoss(nodes.Get(a)->GetObject<MobilityModel>(),
                          nodes.Get(b)->GetObject<MobilityModel>(), loss[a * n + b], false);
        }
      }
    }
    Ptr<YansWifiChannel> channel = CreateObject<YansWifiChannel>();
    channel->SetPropagationLossModel(matrix);
    channel->SetPropagationDelayModel(CreateObject<ConstantSpeedPropagationDelayModel>());
    YansWifiPhyHelper phy;
    phy.SetChannel(channel);
    phy.Set("TxPowerStart", DoubleValue(txPowerDbm));
    phy.Set("TxPowerEnd", DoubleValue(txPowerDbm));
    phy.Set("RxSensitivity", DoubleValue(sensitivityDbm));
    phy.Set("RxNoiseFigure", DoubleValue(noiseFigureDb));
    phy.SetErrorRateModel("ns3::NistErrorRateModel");
    phy.SetPreambleDetectionModel("ns3::ThresholdPreambleDetectionModel",
                                  "MinimumRssi", DoubleValue(sensitivityDbm));
    WifiMacHelper mac;
    mac.SetType("ns3::AdhocWifiMac");
    NetDeviceContainer devices = wifi.Install(phy, mac, nodes);
    InternetStackHelper internet;
    internet.SetIpv6StackInstall(false);
    internet.Install(nodes);
    Ipv4AddressHelper address;
    address.SetBase("10.1.0.0", "255.255.0.0");
    address.Assign(devices);
    for (uint32_t i = 0; i < n; ++i) {
      DynamicCast<WifiNetDevice>(devices.Get(i))->GetPhy()->TraceConnectWithoutContext(
          "PhyTxBegin", MakeBoundCallback(&TxBegin, i));
      UdpServerHelper serverHelper(9);
      ApplicationContainer server = serverHelper.Install(nodes.Get(i));
      server.Start(Seconds(0.0));
      server.Get(0)->TraceConnectWithoutContext("RxWithAddresses", MakeBoundCallback(&Received, i));
    }
    for (uint32_t i = 0; i < senders; ++i) {
      UdpClientHelper client(InetSocketAddress(Ipv4Address("255.255.255.255"), 9));
      client.SetAttribute("MaxPackets", UintegerValue(0));
      client.SetAttribute("Interval", TimeValue(Seconds(interval)));
      client.SetAttribute("PacketSize", UintegerValue(payloadBytes));
      ApplicationContainer app = client.Install(nodes.Get(i));
      app.Start(Seconds(starts[i]));
      app.Stop(Seconds(stopS));
    }
    Simulator::Stop(Seconds(stopS));
    Simulator::Run();
    Simulator::Destroy();
  }
  std::vector<double> out(g_tx);
  out.insert(out.end(), g_rx.begin(), g_rx.end());
  out.insert(out.end(), g_delay.begin(), g_delay.end());
  return out;
}
}  // namespace mrcomm_contention
"""


@dataclass(frozen=True)
class Setup:
    """One case's nodes: the first ``senders`` send; ``loss[a, b]`` dB from a to b;
    ``receivers``: the nodes whose receptions are measured."""

    case: str
    senders: int
    loss: np.ndarray
    starts: list[float]
    interval: float
    receivers: list[int]


def setup(case: str, senders: int, profile: RadioProfile, seed: int) -> Setup:
    """The nodes, powers and traffic of one case (see the module docstring)."""
    rng = np.random.default_rng(seed)
    if case == "hidden":
        n = senders + LISTENERS
        near = profile.reference_loss_db + 10 * profile.exponent * math.log10(5.0)  # 5 m
        loss = np.full((n, n), APART_DB)
        group = np.arange(senders) % 2
        for a in range(n):
            for b in range(n):
                if a < senders and b < senders and group[a] == group[b]:
                    loss[a, b] = near
                elif a >= senders or b >= senders:
                    loss[a, b] = near + LISTENER_MARGIN_DB
        np.fill_diagonal(loss, 0.0)
        starts = (rng.random(senders) * 0.01 + 0.1).tolist()
        return Setup(case, senders, loss, starts, SATURATED_INTERVAL_S, list(range(senders, n)))
    loss = _circle_loss(profile, senders)
    if case == "saturated":
        starts = (rng.random(senders) * 0.01 + 0.1).tolist()
        return Setup(case, senders, loss, starts, SATURATED_INTERVAL_S, list(range(senders)))
    starts = (rng.random(senders) * POSE_INTERVAL_S + 0.1).tolist()
    return Setup(case, senders, loss, starts, POSE_INTERVAL_S, list(range(senders)))


def _circle_loss(profile: RadioProfile, n: int) -> np.ndarray:
    """Log-distance loss between n nodes on a 5 m circle (the profile's law)."""
    angle = 2 * math.pi * np.arange(n) / n
    xy = 5.0 * np.c_[np.cos(angle), np.sin(angle)]
    d = np.maximum(np.linalg.norm(xy[:, None] - xy[None], axis=-1), 1.0)
    loss = profile.reference_loss_db + 10 * profile.exponent * np.log10(d)
    np.fill_diagonal(loss, 0.0)
    return np.asarray(loss)


@dataclass
class Outcome:
    """Frames sent, received at the measured receivers, and delays."""

    sent: float
    expected: float  # frames sent times the measured receivers in range of each
    received: float
    delay_sum: float
    seconds: float
    receivers: int
    cpu_s: float

    @property
    def delivery(self) -> float:
        return self.received / self.expected if self.expected else math.nan

    @property
    def throughput_kbps(self) -> float:
        bits = self.received * PAYLOAD_BYTES * 8
        return bits / self.seconds / self.receivers / 1e3

    @property
    def delay_ms(self) -> float:
        return 1e3 * self.delay_sum / self.received if self.received else math.nan


def pooled(outcomes: Sequence[Outcome]) -> Outcome:
    """Several seeds' outcomes of one case as one: frames, receptions, delays and
    seconds summed (the ratios over all of them)."""
    return Outcome(
        sum(o.sent for o in outcomes), sum(o.expected for o in outcomes),
        sum(o.received for o in outcomes), sum(o.delay_sum for o in outcomes),
        sum(o.seconds for o in outcomes), outcomes[0].receivers,
        sum(o.cpu_s for o in outcomes),
    )  # fmt: skip


def _in_range(s: Setup, profile: RadioProfile) -> np.ndarray:
    power = profile.tx_power_dbm - s.loss
    return (power >= profile.sensitivity_dbm) & ~np.eye(len(s.loss), dtype=bool)


def run_ns3(ns: Any, s: Setup, profile: RadioProfile, stop: float, seed: int) -> Outcome:
    n = len(s.loss)
    start = time.process_time()
    out = list(
        ns.cppyy.gbl.mrcomm_contention.Run(
            n, s.senders,
            ns.cppyy.gbl.std.vector["double"](s.loss.ravel().tolist()),
            profile.tx_power_dbm, profile.sensitivity_dbm, noise_figure_db(profile),
            ns.cppyy.gbl.std.vector["double"](s.starts),
            s.interval, stop, PAYLOAD_BYTES, seed, 1,
        )
    )  # fmt: skip
    cpu = time.process_time() - start
    tx, rx, delay = np.array(out[:n]), np.array(out[n : 2 * n]), np.array(out[2 * n :])
    reach = _in_range(s, profile)[:, s.receivers].sum(axis=1)
    return Outcome(
        float(tx.sum()), float((tx * reach).sum()), float(rx[s.receivers].sum()),
        float(delay[s.receivers].sum()), stop - min(s.starts), len(s.receivers), cpu,
    )  # fmt: skip


def run_model(s: Setup, profile: RadioProfile, stop: float, seed: int) -> Outcome:
    """The same traffic through :class:`SharedMedium`, each frame submitted at its
    instant, with ns-3's reception rule for the outcome at each receiver."""
    n = len(s.loss)
    start = time.process_time()
    rngs = [np.random.default_rng([seed, i]) for i in range(n)]
    draws = np.random.default_rng([seed, 9999])
    medium = SharedMedium(profile, n, rngs)
    power = profile.tx_power_dbm - s.loss
    np.fill_diagonal(power, np.nan)
    medium.set_power(power)
    bits = (PAYLOAD_BYTES + OVERHEAD_BYTES) * 8
    noise = profile.noise_floor_dbm
    # Publication instants of every sender, merged in time order.
    instants = sorted(
        (t, i) for i in range(s.senders) for t in np.arange(s.starts[i], stop, s.interval).tolist()
    )
    # A saturated sender keeps a bounded backlog (ns-3's queue holds 500 packets).
    cap = 500
    sent = expected = received = delay = 0.0
    reach = _in_range(s, profile)[:, s.receivers]
    targets = np.array(s.receivers)

    def finish(frames: Sequence[Any]) -> None:
        nonlocal sent, expected, received, delay
        for frame in frames:
            if frame.dropped:
                continue
            sent += 1
            expected += reach[frame.sender].sum()
            for r in targets[reach[frame.sender]].tolist():
                if frame.blocked[r]:
                    continue
                sinr = power[frame.sender, r] - 10 * math.log10(
                    10 ** (noise / 10) + frame.interference_mw[r]
                )
                if draws.random() >= per(ber(sinr + noise, noise, profile, False), bits):
                    received += 1
                    delay += frame.delay

    for t, i in instants:
        finish(medium.advance(t))
        if medium.queued(i) < cap:
            medium.submit(i, t, bits, None)
        finish(medium.advance(t))
    finish(medium.advance(stop))
    cpu = time.process_time() - start
    return Outcome(sent, expected, received, delay, stop - min(s.starts), len(s.receivers), cpu)


def contention_profile(name: str = DEFAULT_PROFILE) -> RadioProfile:
    """The bundled profile with ns-3's reception rule (DSSS, 4 dB preamble)."""
    base = load_profile(name)
    # ns-3's MAC queue drops a packet older than 500 ms (WifiMacQueue MaxDelay).
    update = {"modulation": "dsss", "preamble_snr_db": 4.0, "max_queue_s": 0.5}
    return base.model_copy(update=update)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results"))
    parser.add_argument("--figure", type=Path, default=None)
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated seconds per case")
    parser.add_argument(
        "--seeds", type=int, nargs="+", default=[1],
        help="seeds (each its own start instants and draws); the outcomes are pooled",
    )  # fmt: skip
    parser.add_argument("--senders", type=int, nargs="*", default=list(SENDERS))
    parser.add_argument(
        "--replot", type=Path, default=None,
        help="draw --figure and print the table from a CSV this script wrote (no ns-3)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.replot is not None:
        rows = read_rows(args.replot)
        print(markdown(rows))
        if args.figure is not None:
            figure(rows, args.figure)
        return 0
    with _filtered_stderr():
        try:
            from ns import ns  # type: ignore[import-not-found,unused-ignore]

            ns.cppyy.cppdef(_CPP)
        except (ImportError, SystemExit):
            print(INSTALL_HINT, file=sys.stderr)
            return 2
    profile = contention_profile()
    rows = []
    for case in CASES:
        for senders in args.senders:
            runs = []
            for seed in args.seeds:
                s = setup(case, senders, profile, seed)
                stop = min(s.starts) + args.seconds
                with _filtered_stderr():
                    ns3_side = run_ns3(ns, s, profile, stop, seed)
                runs.append((ns3_side, run_model(s, profile, stop, seed)))
            theirs = pooled([r[0] for r in runs])
            ours = pooled([r[1] for r in runs])
            rows.append((case, senders, theirs, ours))
            print(
                f"{case:9s} {senders:3d}  delivery ns-3 {theirs.delivery:.3f} model "
                f"{ours.delivery:.3f}  throughput {theirs.throughput_kbps:7.1f} "
                f"{ours.throughput_kbps:7.1f} kbit/s  delay {theirs.delay_ms:7.2f} "
                f"{ours.delay_ms:7.2f} ms  cpu {theirs.cpu_s:.1f} / {ours.cpu_s:.1f} s",
                flush=True,
            )
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "ns3_contention.csv"
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "senders", "side", "sent", "received", "delivery",
                    "throughput_kbps", "delay_ms", "cpu_s"])  # fmt: skip
        for case, senders, theirs, ours in rows:
            for side, o in (("ns-3", theirs), ("model", ours)):
                w.writerow([case, senders, side, int(o.sent), int(o.received),
                            f"{o.delivery:.4f}", f"{o.throughput_kbps:.2f}",
                            f"{o.delay_ms:.3f}", f"{o.cpu_s:.2f}"])  # fmt: skip
    print(markdown(rows))
    if args.figure is not None:
        figure(rows, args.figure)
    return 0


def read_rows(path: Path) -> list[tuple[str, int, Outcome, Outcome]]:
    """The rows of a CSV written by :func:`main` (delivery, throughput and delay kept;
    the outcomes rebuilt so that they give them back)."""
    sides: dict[tuple[str, int], dict[str, Outcome]] = {}
    with path.open() as f:
        for rec in csv.DictReader(f):
            received = float(rec["received"])
            delivery = float(rec["delivery"])
            kbps = float(rec["throughput_kbps"])
            outcome = Outcome(
                sent=float(rec["sent"]),
                expected=received / delivery if delivery else math.inf,
                received=received,
                delay_sum=float(rec["delay_ms"]) * received / 1e3,
                seconds=received * PAYLOAD_BYTES * 8 / (kbps * 1e3) if kbps else 1.0,
                receivers=1,
                cpu_s=float(rec["cpu_s"]),
            )
            sides.setdefault((rec["case"], int(rec["senders"])), {})[rec["side"]] = outcome
    return [(case, n, o["ns-3"], o["model"]) for (case, n), o in sides.items()]


def markdown(rows: list[tuple[str, int, Outcome, Outcome]]) -> str:
    lines = [
        "| case | senders | delivery ns-3 | delivery model | Δ | throughput ns-3 (kbit/s) "
        "| throughput model | Δ % | delay ns-3 (ms) | delay model (ms) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for case, senders, theirs, ours in rows:
        dt = 100 * (ours.throughput_kbps / theirs.throughput_kbps - 1)
        lines.append(
            f"| {case} | {senders} | {theirs.delivery:.3f} | {ours.delivery:.3f} | "
            f"{ours.delivery - theirs.delivery:+.3f} | {theirs.throughput_kbps:.1f} | "
            f"{ours.throughput_kbps:.1f} | {dt:+.1f} | {theirs.delay_ms:.2f} | "
            f"{ours.delay_ms:.2f} |"
        )
    return "\n".join(lines)


def figure(rows: list[tuple[str, int, Outcome, Outcome]], path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for case, marker in zip(CASES, "osd", strict=True):
        mine = [r for r in rows if r[0] == case]
        n = [r[1] for r in mine]
        for side, style in ((2, "-"), (3, "--")):
            label = f"{case}, {'ns-3' if side == 2 else 'MRComm'}"
            axes[0].plot(n, [r[side].delivery for r in mine], style, marker=marker, label=label)
            axes[1].plot(n, [r[side].throughput_kbps for r in mine], style, marker=marker)
    axes[0].set(xscale="log", xlabel="senders", ylabel="delivery ratio", ylim=(0, 1.02))
    axes[1].set(xscale="log", xlabel="senders", ylabel="throughput per receiver (kbit/s)")
    counts = sorted({r[1] for r in rows})
    for ax in axes:
        ax.set_xticks(counts, [str(c) for c in counts])
        ax.minorticks_off()
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Shared channel against ns-3 802.11b (DSSS 1 Mbit/s, broadcast)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=150)


if __name__ == "__main__":
    raise SystemExit(main())
