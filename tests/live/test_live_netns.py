"""Live mode over a real (emulated) network: every process in its own Linux network
namespace, joined by veth links, with kernel-level random packet drop (nftables
``numgen random`` on the input hook) — issue 7, "must show":

* LF + AON over Zenoh TCP still delivers every task status at 20 % and 30 % loss
  (and a robot whose links go down for a while keeps running and reconnects);
* a peer whose link goes down both ways, or one way only, for 5, 30 or 120 s,
  reconnects by itself.

The world process (the stand-in for each robot's own body) is spared the drop. Skipped,
with the reason, where namespaces or nftables cannot be used.
"""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml

from mrcomm.live.launcher import LiveTeam
from mrcomm.live.settings import LiveSettings
from mrcomm.net.zenoh_config import make_options
from mrcomm.run.config import make_config

from .helpers import ROOT, S1, s1_variant, wait_for
from .netns import Netns, skip_unless_possible

pytestmark = [pytest.mark.slow, pytest.mark.alone]

PROBE = Path(__file__).with_name("probe_node.py")


@pytest.fixture(scope="module", autouse=True)
def _namespaces_possible() -> None:
    skip_unless_possible()


def short_scenario(directory: Path) -> Path:
    """S1's map, team and start with one task per robot near the start room: S1's
    tasks 3 and 6 (the conference room's corners) and one more in that room (a mission
    of about 75 simulated seconds)."""
    tasks = [t for t in yaml.safe_load((S1.parent / "s1_tasks.yaml").read_text())]
    near = [t for t in tasks if t["task_id"] in ("3", "6")]
    near.append({**near[0], "task_id": "8", "location": {"x": 27.5, "y": 11.0}})
    return s1_variant(directory, "S1-near", near)


@pytest.mark.parametrize(("loss", "speed", "outage"), [(20, 4.0, True), (30, 2.0, False)])
def test_lf_aon_delivers_every_status_under_kernel_loss(
    loss: int, speed: float, outage: bool, tmp_path: Path
) -> None:
    run = make_config(
        None, scenario=short_scenario(tmp_path), behaviour="lf", threshold="slt", max_time=900.0
    )
    records = tmp_path / "records"
    settings = LiveSettings(run, make_options(), records, speed=speed)
    names = ("world", "robot_1", "robot_2", "robot_3")
    robots = names[1:]
    with Netns(names, spared=("world",)) as net:
        wrappers = {n: net.wrapper(n) for n in names}
        with LiveTeam(settings, addresses=net.ip, wrappers=wrappers) as team:
            team.start()
            # The loss starts with the mission, once every robot's clock runs: under
            # 30 % loss TCP's retransmission back-off can hold a session's opening past
            # any start time-out (seen on this 2-core VM: 3 starts in 9 missed 60 s,
            # one of them 180 s), and what is tested here is the mission under loss.
            wait_for(lambda: all(_sim_time(records, r) > 0.0 for r in robots), 120, "the start")
            for name in robots:
                net.set_faults(name, loss=loss)
            if outage:
                # robot_3 loses every peer for 5 s mid-mission, then comes back.
                wait_for(lambda: _sim_time(records, "robot_3") > 15.0, 120, "the mission")
                net.set_faults("robot_3", down=True)
                down_at = time.monotonic()
                wait_for(lambda: time.monotonic() - down_at >= 5.0, 10, "5 s of outage")
                net.set_faults("robot_3", loss=loss)
            team.wait()
            result, report = team.collect()
    mission = result.mission
    assert mission["successful"] is True, mission  # every status reached the assigner
    assert mission["timed_out"] is False
    assert result.aon["total"]["pending"] == 0  # ... and every member, with AON
    assert report["processes"]["robot_3"]["finished"] == [True]  # kept running
    latency = report["pose_latency_ms"]
    print(f"\nkernel loss {loss} % TCP: pose age p50 {latency['p50']} ms, p95 {latency['p95']} ms")


def _sim_time(records: Path, process: str) -> float:
    latest = 0.0
    for path in records.glob(f"{process}.*.jsonl"):
        for raw in path.read_text().splitlines()[-50:]:
            try:
                line = json.loads(raw)
            except json.JSONDecodeError:
                continue
            if line.get("k") == "clock":
                latest = max(latest, float(line["sim"]))
    return latest


class Probe:
    """A probe peer in a namespace; collects what it receives from its peer."""

    def __init__(self, net: Netns, name: str, peer: str, seconds: float) -> None:
        args = [
            sys.executable, str(PROBE), name, f"tcp/{net.ip[name]}:7447",
            f"tcp/{net.ip[peer]}:7447", str(seconds), "20", "tcp", "2",
        ]  # fmt: skip
        self.process = subprocess.Popen(
            net.wrapper(name) + args, stdout=subprocess.PIPE, text=True, cwd=ROOT
        )
        self.lines: queue.SimpleQueue[tuple[float, dict[str, object]]] = queue.SimpleQueue()
        self.last_seq = 0
        self.last_at = 0.0
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for raw in self.process.stdout:
            self.lines.put((time.monotonic(), json.loads(raw)))

    def receiving_since(self, since: float) -> bool:
        """True once a pose newer than any before ``since`` has arrived after it."""
        while True:
            try:
                at, line = self.lines.get_nowait()
            except queue.Empty:
                return self.last_at > since
            seq = line.get("seq")
            if isinstance(seq, int) and seq > self.last_seq:
                self.last_seq = seq
                self.last_at = at

    def stop(self) -> None:
        self.process.terminate()
        self.process.wait(timeout=20)


# The 120 s outages on request (MRCOMM_LONG_OUTAGES=1): four minutes of make test.
OUTAGES = [5.0, 30.0] + ([120.0] if os.environ.get("MRCOMM_LONG_OUTAGES") == "1" else [])


@pytest.mark.parametrize("one_way", [False, True], ids=["both-ways", "one-way"])
@pytest.mark.parametrize("seconds", OUTAGES)
def test_peer_reconnects_by_itself_after_an_outage(seconds: float, one_way: bool) -> None:
    # A 2 s Zenoh link lease: even a 5 s outage outlives the session, so the peers
    # must really reconnect.
    with Netns(("a", "b")) as net:
        a = Probe(net, "a", "b", seconds + 120.0)
        b = Probe(net, "b", "a", seconds + 120.0)
        try:
            start = time.monotonic()
            wait_for(lambda: a.receiving_since(start) and b.receiving_since(start), 30, "traffic")
            net.set_faults("b", down=True)  # b hears nothing
            if not one_way:
                net.set_faults("a", down=True)
            down_at = time.monotonic()
            wait_for(lambda: time.monotonic() - down_at >= seconds, seconds + 5, "the outage")
            a.receiving_since(0.0), b.receiving_since(0.0)  # take in what came meanwhile
            assert b.last_at < down_at + 1.0  # the outage was real: b heard nothing
            cut = time.monotonic()
            net.set_faults("a")
            net.set_faults("b")
            wait_for(
                lambda: a.receiving_since(cut) and b.receiving_since(cut),
                60,
                "both peers to hear each other again",
            )
            assert a.process.poll() is None and b.process.poll() is None
        finally:
            a.stop()
            b.stop()
