"""``mrcomm pulse``: run the ESD pulse on a robot.

Polls ``iw dev IFACE station dump`` at ``--rate`` Hz and publishes the RSSI of every
peer listed in ``--peers``. There is no network bus in this command yet: the pulse is
wired to a bus endpoint that writes one JSON line per message to stdout
(``{"topic": "rssi", "type": "rssi", "sender": ..., "peer": ..., "rssi": ...}``). Live
mode puts Zenoh behind the same :class:`~mrcomm.ports.Bus` port, unchanged pulse code.
"""

from __future__ import annotations

import contextlib
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, TextIO

import msgspec
import typer

from mrcomm.messaging.messages import Message
from mrcomm.net.pulse import Pulse, iw_poller, load_peers
from mrcomm.ports import Handler


class JsonLinesBus:
    """A :class:`~mrcomm.ports.Bus` endpoint that prints each published message as a
    JSON line (and delivers it to local subscribers)."""

    def __init__(self, owner: str, stream: TextIO) -> None:
        self._owner = owner
        self.stream = stream
        self._handlers: dict[str, list[Handler]] = {}

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        record = {"topic": topic, **msgspec.to_builtins(message)}
        # Flush per line: a consumer reading the pipe must see readings as they come.
        print(json.dumps(record), file=self.stream, flush=True)
        for handler in self._handlers.get(topic, []):
            handler(message)

    def subscribe(self, topic: str, handler: Handler) -> None:
        self._handlers.setdefault(topic, []).append(handler)


def run_pulse(
    pulse: Pulse,
    *,
    count: int | None,
    clock: Callable[[], float],
    sleep: Callable[[float], None],
) -> None:
    """Step ``pulse`` on a clock until ``count`` polls are done (forever if None)."""
    while True:
        pulse.step(clock())
        if count is not None and pulse.stats.polls >= count:
            return
        due = pulse.next_due
        wait = (due - clock()) if due is not None else pulse.period
        if wait > 0:
            sleep(wait)


def pulse(
    iface: Annotated[str, typer.Option("--iface", help="Wireless interface, e.g. wlan0.")],
    peers: Annotated[
        Path, typer.Option("--peers", help="YAML mapping robot ids <-> MAC addresses.")
    ],
    robot: Annotated[str, typer.Option("--robot", help="Id of the robot this pulse serves.")],
    rate: Annotated[float, typer.Option(help="Polls per second.", min=0.01, max=100.0)] = 2.0,
    count: Annotated[
        int | None,
        typer.Option(help="Stop after this many polls (default: run until interrupted).", min=1),
    ] = None,
) -> None:
    """ESD pulse: publish the measured RSSI of each peer at --rate Hz.

    Messages go to stdout as JSON lines, one per RssiMsg.

    Live mode will put Zenoh behind the same bus port.
    """
    peer_map = load_peers(peers)
    poll = iw_poller(iface)
    bus = JsonLinesBus(f"{robot}/pulse", sys.stdout)
    runner = Pulse(bus, robot, peer_map, poll, 1.0 / rate, incarnation=time.time_ns() // 1_000_000)
    with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C is the normal way to stop
        run_pulse(runner, count=count, clock=time.time, sleep=time.sleep)
    stats = runner.stats
    typer.echo(
        f"pulse {robot}: {stats.polls} polls, {stats.published} readings published, "
        f"{stats.poll_errors} poll errors, {stats.parse_errors} parse errors, "
        f"{len(stats.unknown)} unknown stations",
        err=True,
    )
