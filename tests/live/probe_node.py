"""A probe peer for the real-network tests and the benchmark (run as a script, e.g.
inside a network namespace): publishes pose messages at a fixed rate on
``mrcomm/<team>/<name>/pose`` through the live-mode Zenoh bus and prints one JSON line
per pose received from a peer: ``{"from": ..., "seq": ..., "age": seconds}``.

    python probe_node.py NAME LISTEN CONNECT[,CONNECT...] SECONDS RATE [tcp|udp] [LEASE]
"""

from __future__ import annotations

import json
import sys
import time

from mrcomm.messaging.messages import TOPIC_POSE, Message, PoseMsg
from mrcomm.net.zenoh_bus import LinkRules, PositionBook, ZenohBus
from mrcomm.net.zenoh_config import make_options
from mrcomm.net.zenoh_node import ZenohNode
from mrcomm.seeding import stream


def main(argv: list[str]) -> int:
    name, listen, connect, seconds, rate = argv[:5]
    protocol = argv[5] if len(argv) > 5 else "tcp"
    lease = float(argv[6]) if len(argv) > 6 else 10.0
    options = make_options(
        team="probe",
        listen=[listen],
        connect=[c for c in connect.split(",") if c],
        protocol=protocol,
        link_lease=lease,
    )
    node = ZenohNode(options)
    bus = ZenohBus(node, LinkRules(), PositionBook())
    endpoint = bus.endpoint(name, stream(1, "loss", name))

    def on_pose(message: Message) -> None:
        print(json.dumps({"from": message.sender, "seq": message.seq}), flush=True)

    endpoint.subscribe(TOPIC_POSE, on_pose)
    period = 1.0 / float(rate)
    start = time.monotonic()
    seq = 0
    due = start
    reported = 0
    while time.monotonic() - start < float(seconds):
        now = time.monotonic()
        if now >= due:
            seq += 1
            endpoint.publish(
                TOPIC_POSE,
                PoseMsg(sender=name, incarnation=1, seq=seq, stamp=now - start, x=0, y=0, theta=0),
            )
            due += period
        item = node.poll(max(min(due - time.monotonic(), 0.05), 0.0))
        while item is not None:
            if item.channel == "bus":
                bus.handle(item)
            item = node.poll(None)
        for age in bus.pose_latency[reported:]:
            print(json.dumps({"age": round(age, 6)}), flush=True)
        reported = len(bus.pose_latency)
    print(json.dumps({"sent": seq}), flush=True)
    node.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
