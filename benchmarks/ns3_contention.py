"""The shared channel (``network.channel: shared``, :mod:`mrcomm.net.radio.medium`)
against ns-3's 802.11 with the same nodes, the same received powers and the same
traffic. A benchmark, not a dependency:

    pip install ns3            # into the project venv (make ns3-validation does it)
    python benchmarks/ns3_contention.py [--out DIR] [--figure PATH] [--seconds S] [--seeds 1 2 3]

Three cases, each for 2, 5, 10, 20 and 50 senders, for each of ``--seeds`` (each seed
its own start instants and draws on both sides; the outcomes pooled, and a bootstrap over
the seeds gives the throughput difference its 95 % interval):

* ``saturated``: every sender always has a frame waiting (a packet every 0.5 ms, more
  than the channel carries), all within range of each other (on a 5 m circle);
* ``poses``: the team's real traffic, a 150-byte pose every 0.2 s per sender (5 Hz,
  each sender's first at a uniform instant of the first 0.2 s), all in range;
* ``hidden``: the senders in two groups that cannot hear each other (200 dB apart),
  saturated, and four listeners between them that hear both groups 10 dB weaker than
  a group hears itself: every frame a listener hears may meet a hidden one. Each sender
  has a payload of its own, 100–200 bytes (drawn per seed). With one size for all
  (``--hidden-sizes same``) every frame lasts the same and every gap is DIFS plus whole
  slots, so the two groups keep their phase on the 20 µs slot lattice and it wanders
  slowly: a listener receives only when one group starts in the other's gap, and a
  10 s run at 10–50 senders is a lottery on both sides (at 50 senders, per seed, 0.1
  to 42 kbit/s in either simulator).

For each: the delivery ratio (frames received over frames sent times the receivers in
range; in ``hidden``, at the listeners), the throughput (bits of payload received per
second per receiver) and, for ``poses``, the mean delay from a packet's publication to
its reception. Only what ends before the last publication counts, on both sides.
Both sides broadcast (no acknowledgement, no retry) 150-byte payloads (but ``hidden``'s),
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

from mrcomm.analysis.inference import bootstrap_ci
from mrcomm.net.radio.medium import SharedMedium
from mrcomm.net.radio.profile import DEFAULT_PROFILE, RadioProfile, load_profile

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
#: The smallest and largest payload of a ``hidden`` sender, bytes.
HIDDEN_PAYLOADS = (100, 200)

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
static std::vector<double> g_bits;

static void TxBegin(uint32_t node, ns3::Ptr<const ns3::Packet>, double) { g_tx[node] += 1; }

static void Received(uint32_t node, ns3::Ptr<const ns3::Packet> packet, const ns3::Address&,
                     const ns3::Address&) {
  ns3::Ptr<ns3::Packet> copy = packet->Copy();
  ns3::SeqTsHeader header;
  copy->RemoveHeader(header);
  g_rx[node] += 1;
  g_bits[node] += 8.0 * packet->GetSize();
  g_delay[node] += (ns3::Simulator::Now() - header.GetTs()).GetSeconds();
}

// n nodes, the first `senders` of them sending; loss[a * n + b] dB from a to b.
// Returns tx frames of each node, then received packets, the sum of their delays and
// their payload bits.
std::vector<double> Run(uint32_t n, uint32_t senders, const std::vector<double>& loss,
                        double txPowerDbm, double sensitivityDbm, double noiseFigureDb,
                        const std::vector<double>& starts, double interval, double stopS,
                        const std::vector<double>& payloads, uint32_t seed, uint64_t run) {
  using namespace ns3;
  RngSeedManager::SetSeed(seed);
  RngSeedManager::SetRun(run);
  g_tx.assign(n, 0.0);
  g_rx.assign(n, 0.0);
  g_delay.assign(n, 0.0);
  g_bits.assign(n, 0.0);
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
      client.SetAttribute("PacketSize", UintegerValue(static_cast<uint32_t>(payloads[i])));
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
  out.insert(out.end(), g_bits.begin(), g_bits.end());
  return out;
}
}  // namespace mrcomm_contention
"""


@dataclass(frozen=True)
class Setup:
    """One case's nodes: the first ``senders`` send (each its ``payloads`` bytes);
    ``loss[a, b]`` dB from a to b; ``receivers``: the nodes whose receptions are
    measured."""

    case: str
    senders: int
    loss: np.ndarray
    starts: list[float]
    interval: float
    receivers: list[int]
    payloads: list[int]


def setup(
    case: str, senders: int, profile: RadioProfile, seed: int, hidden_sizes: str = "mixed"
) -> Setup:
    """The nodes, powers and traffic of one case (see the module docstring)."""
    rng = np.random.default_rng(seed)
    same = [PAYLOAD_BYTES] * senders
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
        payloads = same
        if hidden_sizes == "mixed":
            payloads = rng.integers(HIDDEN_PAYLOADS[0], HIDDEN_PAYLOADS[1] + 1, senders).tolist()
        listeners = list(range(senders, n))
        return Setup(case, senders, loss, starts, SATURATED_INTERVAL_S, listeners, payloads)
    loss = _circle_loss(profile, senders)
    if case == "saturated":
        starts = (rng.random(senders) * 0.01 + 0.1).tolist()
        return Setup(
            case, senders, loss, starts, SATURATED_INTERVAL_S, list(range(senders)), same
        )  # fmt: skip
    starts = (rng.random(senders) * POSE_INTERVAL_S + 0.1).tolist()
    return Setup(case, senders, loss, starts, POSE_INTERVAL_S, list(range(senders)), same)


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
    """Frames sent, received at the measured receivers (and their payload bits), and
    delays."""

    sent: float
    expected: float  # frames sent times the measured receivers in range of each
    received: float
    delay_sum: float
    seconds: float
    receivers: int
    cpu_s: float
    bits: float

    @property
    def delivery(self) -> float:
        return self.received / self.expected if self.expected else math.nan

    @property
    def throughput_kbps(self) -> float:
        return self.bits / self.seconds / self.receivers / 1e3

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
        sum(o.cpu_s for o in outcomes), sum(o.bits for o in outcomes),
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
            s.interval, stop, ns.cppyy.gbl.std.vector["double"](s.payloads), seed, 1,
        )
    )  # fmt: skip
    cpu = time.process_time() - start
    tx, rx, delay, bits = (np.array(out[k * n : (k + 1) * n]) for k in range(4))
    reach = _in_range(s, profile)[:, s.receivers].sum(axis=1)
    return Outcome(
        float(tx.sum()), float((tx * reach).sum()), float(rx[s.receivers].sum()),
        float(delay[s.receivers].sum()), stop - min(s.starts), len(s.receivers), cpu,
        float(bits[s.receivers].sum()),
    )  # fmt: skip


def run_model(s: Setup, profile: RadioProfile, stop: float, seed: int) -> Outcome:
    """The same traffic through :class:`SharedMedium`, each frame submitted at its
    instant; each receiver's outcome drawn from the frame's error with the other frames
    (``Frame.shared``, as the bus draws it)."""
    n = len(s.loss)
    start = time.process_time()
    rngs = [np.random.default_rng([seed, i]) for i in range(n)]
    draws = np.random.default_rng([seed, 9999])
    medium = SharedMedium(profile, n, rngs)
    power = profile.tx_power_dbm - s.loss
    np.fill_diagonal(power, np.nan)
    medium.set_power(power)
    # Publication instants of every sender, merged in time order.
    instants = sorted(
        (t, i) for i in range(s.senders) for t in np.arange(s.starts[i], stop, s.interval).tolist()
    )
    # A saturated sender keeps a bounded backlog (ns-3's queue holds 500 packets).
    cap = 500
    sent = expected = received = delay = payload_bits = 0.0
    reach = _in_range(s, profile)[:, s.receivers]
    targets = np.array(s.receivers)

    def finish(frames: Sequence[Any]) -> None:
        nonlocal sent, expected, received, delay, payload_bits
        for frame in frames:
            if frame.dropped:
                continue
            sent += 1
            expected += reach[frame.sender].sum()
            for r in targets[reach[frame.sender]].tolist():
                if frame.blocked[r]:
                    continue
                if draws.random() >= frame.shared[r]:
                    received += 1
                    delay += frame.delay
                    payload_bits += frame.bits - OVERHEAD_BYTES * 8

    for t, i in instants:
        finish(medium.advance(t))
        if medium.queued(i) < cap:
            medium.submit(i, t, (s.payloads[i] + OVERHEAD_BYTES) * 8, None)
        finish(medium.advance(t))
    finish(medium.advance(stop))
    cpu = time.process_time() - start
    return Outcome(
        sent, expected, received, delay, stop - min(s.starts), len(s.receivers), cpu,
        payload_bits,
    )  # fmt: skip


def contention_profile(name: str = DEFAULT_PROFILE) -> RadioProfile:
    """The bundled profile with ns-3's reception rule (DSSS, 4 dB preamble)."""
    base = load_profile(name)
    # ns-3's MAC queue drops a packet older than 500 ms (WifiMacQueue MaxDelay).
    update = {"modulation": "dsss", "preamble_snr_db": 4.0, "max_queue_s": 0.5}
    return base.model_copy(update=update)


#: One case's outcomes, seed by seed: (case, senders, ns-3's, the model's).
Row = tuple[str, int, list[Outcome], list[Outcome]]
#: The per-seed outcomes' columns in the CSV (the Outcome's fields).
FIELDS = ("sent", "expected", "received", "delay_sum", "seconds", "receivers", "cpu_s", "bits")


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
    parser.add_argument("--cases", nargs="+", choices=CASES, default=list(CASES))
    parser.add_argument(
        "--hidden-sizes", choices=("mixed", "same"), default="mixed",
        help="hidden senders' payloads: 100-200 bytes each (mixed) or 150 bytes for all",
    )  # fmt: skip
    parser.add_argument(
        "--replot", type=Path, default=None,
        help="draw --figure and print the table from a CSV this script wrote (no ns-3)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.replot is not None:
        try:
            recorded = read_rows(args.replot)
            if not recorded:
                raise ValueError("no rows")
        except (OSError, KeyError, ValueError) as error:
            parser.error(f"--replot {args.replot}: not a CSV this script wrote ({error!r})")
        print(markdown(recorded))
        if args.figure is not None:
            figure(recorded, args.figure)
        return 0
    with _filtered_stderr():
        try:
            from ns import ns  # type: ignore[import-not-found,unused-ignore]

            ns.cppyy.cppdef(_CPP)
        except (ImportError, SystemExit):
            print(INSTALL_HINT, file=sys.stderr)
            return 2
    profile = contention_profile()
    rows: list[Row] = []
    for case in args.cases:
        for senders in args.senders:
            theirs, ours = [], []
            for seed in args.seeds:
                s = setup(case, senders, profile, seed, args.hidden_sizes)
                stop = min(s.starts) + args.seconds
                with _filtered_stderr():
                    theirs.append(run_ns3(ns, s, profile, stop, seed))
                ours.append(run_model(s, profile, stop, seed))
            rows.append((case, senders, theirs, ours))
            a, b = pooled(theirs), pooled(ours)
            print(
                f"{case:9s} {senders:3d}  delivery ns-3 {a.delivery:.3f} model "
                f"{b.delivery:.3f}  throughput {a.throughput_kbps:7.1f} "
                f"{b.throughput_kbps:7.1f} kbit/s  delay {a.delay_ms:7.2f} "
                f"{b.delay_ms:7.2f} ms  cpu {a.cpu_s:.1f} / {b.cpu_s:.1f} s",
                flush=True,
            )
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "ns3_contention.csv"
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "senders", "seed", "side", *FIELDS])
        for case, senders, theirs, ours in rows:
            for side, outcomes in (("ns-3", theirs), ("model", ours)):
                for seed, o in zip(args.seeds, outcomes, strict=True):
                    w.writerow([case, senders, seed, side, *(getattr(o, k) for k in FIELDS)])
    print(markdown(rows))
    if args.figure is not None:
        figure(rows, args.figure)
    return 0


def read_rows(path: Path) -> list[Row]:
    """The per-seed outcomes of a CSV written by :func:`main`."""
    sides: dict[tuple[str, int], dict[str, list[Outcome]]] = {}
    with path.open() as f:
        for rec in csv.DictReader(f):
            values = [float(rec[k]) for k in FIELDS]
            sent, expected, received, delay_sum, seconds, receivers, cpu_s, bits = values
            outcome = Outcome(
                sent, expected, received, delay_sum, seconds, int(receivers), cpu_s, bits
            )  # fmt: skip
            key = (rec["case"], int(rec["senders"]))
            sides.setdefault(key, {"ns-3": [], "model": []})[rec["side"]].append(outcome)
    return [(case, n, o["ns-3"], o["model"]) for (case, n), o in sides.items()]


def throughput_interval(theirs: list[Outcome], ours: list[Outcome]) -> tuple[float, float]:
    """95 % interval of the throughput's difference, % of ns-3's, by the project's
    bootstrap over the seeds (each side's seeds resampled independently). Every seed
    runs the same seconds with the same receivers, so the pooled throughput is the mean
    of the seeds'."""
    samples = [np.array([o.throughput_kbps for o in side]) for side in (theirs, ours)]

    def difference(a: np.ndarray, b: np.ndarray, axis: int = -1) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.asarray(100 * (b.mean(axis=axis) / a.mean(axis=axis) - 1))

    return bootstrap_ci(samples, difference)


def markdown(rows: list[Row]) -> str:
    lines = [
        "| case | senders | delivery ns-3 | delivery model | Δ | throughput ns-3 (kbit/s) "
        "| throughput model | Δ % [95 % interval] | delay ns-3 (ms) | delay model (ms) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for case, senders, their_seeds, our_seeds in rows:
        theirs, ours = pooled(their_seeds), pooled(our_seeds)
        dt = 100 * (ours.throughput_kbps / theirs.throughput_kbps - 1)
        low, high = throughput_interval(their_seeds, our_seeds)
        lines.append(
            f"| {case} | {senders} | {theirs.delivery:.3f} | {ours.delivery:.3f} | "
            f"{ours.delivery - theirs.delivery:+.3f} | {theirs.throughput_kbps:.1f} | "
            f"{ours.throughput_kbps:.1f} | {dt:+.1f} [{low:+.1f}, {high:+.1f}] | "
            f"{theirs.delay_ms:.2f} | {ours.delay_ms:.2f} |"
        )
    return "\n".join(lines)


def figure(rows: list[Row], path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for case, marker in zip(CASES, "osd", strict=True):
        mine = [r for r in rows if r[0] == case]
        n = [r[1] for r in mine]
        for name, style, outcomes in (
            ("ns-3", "-", [pooled(r[2]) for r in mine]),
            ("MRComm", "--", [pooled(r[3]) for r in mine]),
        ):
            label = f"{case}, {name}"
            axes[0].plot(n, [o.delivery for o in outcomes], style, marker=marker, label=label)
            axes[1].plot(n, [o.throughput_kbps for o in outcomes], style, marker=marker)
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
