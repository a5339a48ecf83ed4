"""``mrcomm pulse``: run a robot's ESD pulse.

The pulse reads either the wireless card (``--iface IFACE --peers PEERS.yaml``: polls
``iw dev IFACE station dump`` at ``--rate`` Hz on this host's clock) or a recorded
trace (``--trace CSV``: replays what ``--robot`` measured, on the world's shared clock
of a live mission), and publishes one RSSI message per peer and reading:

* over Zenoh on ``mrcomm/<team>/<robot>-pulse/rssi`` as soon as any Zenoh option is
  given (``--connect``, ``--listen``, ``--world-connect``, ``--multicast``,
  ``--zenoh-config``; the same options as ``mrcomm agent``), which is what the robot's
  agent listens to;
* as JSON lines on stdout (``{"topic": "rssi", "type": "rssi", "sender": ..., "peer":
  ..., "rssi": ...}``) when no Zenoh option is given, or in addition with
  ``--stdout``.
"""

from __future__ import annotations

import contextlib
import json
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, TextIO

import msgspec
import typer

from mrcomm.cli.zenoh_cli import ZenohCli, warn_insecure, with_zenoh_options
from mrcomm.errors import InputError
from mrcomm.live.journal import new_incarnation
from mrcomm.messaging.messages import TOPIC_RSSI, Message
from mrcomm.net.pulse import Pulse, PulseBase, ReplayPulse, iw_poller, load_peers, pulse_id
from mrcomm.net.zenoh_config import check_key_chunk
from mrcomm.net.zenoh_node import ZenohNode
from mrcomm.ports import Bus, Handler


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
    pulse: PulseBase,
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


@with_zenoh_options
def pulse(
    robot: Annotated[str, typer.Option("--robot", help="Id of the robot this pulse serves.")],
    net: ZenohCli,
    iface: Annotated[
        str | None, typer.Option("--iface", help="Wireless interface to read, e.g. wlan0.")
    ] = None,
    peers: Annotated[
        Path | None,
        typer.Option("--peers", help="With --iface: YAML mapping robot ids <-> MAC addresses."),
    ] = None,
    trace: Annotated[
        Path | None,
        typer.Option(
            "--trace",
            help="Instead of --iface: replay what --robot measured in this RSSI trace CSV "
            "(time,from,to,rssi), on the world's clock (needs Zenoh options).",
        ),
    ] = None,
    rate: Annotated[float, typer.Option(help="Polls per second.", min=0.01, max=100.0)] = 2.0,
    count: Annotated[
        int | None,
        typer.Option(help="Stop after this many polls (default: run until interrupted).", min=1),
    ] = None,
    stdout: Annotated[
        bool,
        typer.Option(
            "--stdout",
            help="Also print each reading as a JSON line (the default output when no "
            "Zenoh option is given).",
        ),
    ] = False,
    world_connect: Annotated[
        list[str] | None,
        typer.Option(
            "--world-connect",
            help="With --trace: the world's endpoint (its clock), on a session of its own "
            "(repeatable; default: the clock is heard over the --connect session).",
        ),
    ] = None,
) -> None:
    """ESD pulse: publish the measured RSSI of each peer at --rate Hz.

    Reads the wireless card (--iface, --peers) on this host's clock, or replays a
    recorded trace (--trace) on the world's shared clock of a live mission. With any
    Zenoh option (--connect, --listen, --world-connect, --multicast, --zenoh-config)
    it publishes over Zenoh on mrcomm/<team>/<robot>-pulse/rssi, which the robot's
    agent listens to; without one it prints JSON lines on stdout (--stdout: both).
    It needs no agent and keeps running when the agent dies.
    """
    use_zenoh = net.joins or bool(world_connect)
    if (iface is None) == (trace is None):
        raise InputError("give either --iface (and --peers) or --trace", field="--iface")
    if iface is not None and peers is None:
        raise InputError("reading the card needs the robots' MAC addresses", field="--peers")
    if trace is not None and not use_zenoh:
        raise InputError(
            "a trace is replayed on the world's clock: give the world's endpoint "
            "(--world-connect or --connect)",
            field="--trace",
        )
    if world_connect and trace is None:
        raise InputError(
            "only a replayed --trace runs on the world's clock", field="--world-connect"
        )
    owner = pulse_id(check_key_chunk(robot, "--robot"))
    zenoh = world = None
    if use_zenoh:
        # A pulse runs on its robot and presents the robot's certificate.
        security = net.security(robot, None)
        zenoh = net.options(security)
        if world_connect:
            world = net.world_options(world_connect, security)
    period = 1.0 / rate
    incarnation = new_incarnation(None, owner)  # a pulse keeps no journal
    bus = FanOutBus(owner)
    runner: PulseBase
    if trace is not None:
        from mrcomm.net.signal.trace import RssiTrace

        recording = RssiTrace.load(trace)
        runner = ReplayPulse(bus, robot, recording, period, incarnation=incarnation, source=trace)
    else:
        assert iface is not None and peers is not None
        peer_map = load_peers(peers)
        poll = iw_poller(iface)
        runner = Pulse(bus, robot, peer_map, poll, period, incarnation=incarnation)
    if stdout or zenoh is None:
        bus.targets.append(JsonLinesBus(owner, sys.stdout))
    # Every input has been checked: only now open the sessions.
    warn_insecure(net.insecure and zenoh is not None)
    with contextlib.ExitStack() as stack:
        clock: ZenohNode | None = None
        if zenoh is not None:
            from mrcomm.live.pulse import PublishingEndpoint

            node = ZenohNode(zenoh)
            stack.callback(node.close)
            bus.targets.append(PublishingEndpoint(node, owner, (TOPIC_RSSI,)))
            clock = node
            if world is not None:
                clock = ZenohNode(world, inbox=node.inbox)
                stack.callback(clock.close)
        # SIGTERM (how a launcher stops it) ends the pulse like Ctrl-C: sessions close.
        previous = signal.signal(signal.SIGTERM, signal.default_int_handler)
        stack.callback(signal.signal, signal.SIGTERM, previous)
        with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C is the normal way to stop
            if clock is not None and trace is not None:
                from mrcomm.live.pulse import run_on_shared_clock

                why = run_on_shared_clock(runner, clock, count=count)
                typer.echo(f"pulse {robot}: stopped: {why}", err=True)
            else:
                run_pulse(runner, count=count, clock=time.time, sleep=time.sleep)
    stats = runner.stats
    typer.echo(
        f"pulse {robot}: {stats.polls} polls, {stats.published} readings published, "
        f"{stats.poll_errors} poll errors, {stats.parse_errors} parse errors, "
        f"{len(stats.unknown)} unknown stations",
        err=True,
    )


class FanOutBus:
    """The pulse's :class:`~mrcomm.ports.Bus` endpoint: hands every publication to each
    of ``targets`` (Zenoh, stdout or both), added once the sessions are open."""

    def __init__(self, owner: str) -> None:
        self._owner = owner
        self.targets: list[Bus] = []

    @property
    def owner(self) -> str:
        return self._owner

    def publish(self, topic: str, message: Message) -> None:
        for target in self.targets:
            target.publish(topic, message)

    def subscribe(self, topic: str, handler: Handler) -> None:
        raise TypeError(f"{self._owner} only publishes (it has no subscriptions)")
