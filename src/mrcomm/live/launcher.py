"""``mrcomm live``: one live mission on this host, every agent its own OS process.

:class:`LiveTeam` starts the world process and one agent process per robot (plus a
stand-alone task assigner when the scenario does not host it on a robot), each a
Zenoh peer listening on its own loopback port and connecting to all the others (no
router, no single point of failure). With ESD it also starts each robot's pulse,
replaying the run's RSSI trace on the world's clock (``mrcomm pulse --trace``). It
waits for the mission to end, then collects every process's own records
(``live.collect``). Tests and fault experiments use its handles to kill or restart a
process mid-mission.

Each child presents its certificate from the team directory given (``--team-dir``:
mutual TLS and the per-member access-control list) or runs ``--insecure``.
Children run the ``mrcomm`` command line itself, so what the launcher does can be done
by hand on several machines (``mrcomm world`` / ``mrcomm agent``, see docs/LIVE.md).
"""

from __future__ import annotations

import dataclasses
import os
import random
import secrets
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.agents.commands import OPERATOR_ID
from mrcomm.errors import InputError, MissionFailed
from mrcomm.live.collect import collect
from mrcomm.live.kernel_links import Emulation
from mrcomm.live.leftovers import die_with_parent
from mrcomm.live.netns import Netns, remove_stale_namespaces
from mrcomm.live.protocol import WORLD_ID
from mrcomm.live.settings import CONSOLE_TOKEN_ENV, LiveSettings
from mrcomm.net.pulse import pulse_id
from mrcomm.net.signal.trace import RssiTrace
from mrcomm.run.config import param_assignments
from mrcomm.run.result import MissionResult
from mrcomm.run.wiring import pulse_trace_path
from mrcomm.world.scenario import load_scenario

_CLI = "from mrcomm.cli.main import app; app()"
EXIT_GRACE = 15.0  # wall s the agents get to finish after the world has ended
PROGRESS_PERIOD = 0.5  # wall s between progress callbacks while a mission runs


@dataclass
class Child:
    name: str
    port: int
    process: subprocess.Popen[bytes]
    log: Path
    handle: IO[bytes] = field(repr=False)


class LiveTeam:
    """The world and agent processes of one live mission on this host."""

    def __init__(
        self,
        settings: LiveSettings,
        *,
        team_dir: Path | None = None,
        host: str = "127.0.0.1",
        extra_args: dict[str, list[str]] | None = None,
        addresses: dict[str, str] | None = None,
        wrappers: dict[str, list[str]] | None = None,
    ) -> None:
        """``addresses`` / ``wrappers`` place processes elsewhere: each listens on its
        own address (port 7447) and starts under its wrapper command (e.g.
        ``ip netns exec NS``); by default all listen on ``host``, on free ports."""
        if settings.mission is None:  # one identity for every process of the run
            settings = dataclasses.replace(settings, mission=secrets.token_hex(8))
        if team_dir is not None and settings.zenoh.protocol != "tls":
            # A team directory means TLS on every link: the endpoints say so.
            zenoh = dataclasses.replace(settings.zenoh, protocol="tls")
            settings = dataclasses.replace(settings, zenoh=zenoh)
        self.settings = settings
        #: The team directory every child takes its certificate from; None: the
        #: children run ``--insecure`` (no authentication; tests and experiments).
        self.team_dir = team_dir
        self.host = host
        self.extra_args = extra_args or {}
        self.addresses = addresses
        self.wrappers = wrappers or {}
        scenario = load_scenario(settings.run.scenario)
        self.robots = tuple(r.id for r in scenario.robots)
        standalone = scenario.assigner.kind != "robot"
        self.names = (
            WORLD_ID,
            *self.robots,
            *((ASSIGNER_ID,) if standalone else ()),
            *((OPERATOR_ID,) if settings.has_operator else ()),
        )
        #: ESD: one trace-replaying pulse process per robot that measured anything in the
        #: trace (pulse id -> robot); a robot without readings never warns, as in sim.
        self.pulses: dict[str, str] = {}
        run = settings.run
        trace = pulse_trace_path(run)
        if trace is not None:
            measuring = {a for a, _ in RssiTrace.load(trace).pairs}
            self.pulses = {pulse_id(r): r for r in self.robots if r in measuring}
        self.ports: dict[str, int] = {}
        self.children: dict[str, Child] = {}
        #: Processes that died during the mission, one line each (after :meth:`wait`).
        self.died: list[str] = []
        self.restarts: dict[str, int] = {}
        #: Agent processes seen exited while the mission runs: when first seen so.
        self.gone: dict[str, float] = {}

    # -- processes ---------------------------------------------------------------------
    def start(self, hold: Collection[str] = ()) -> None:
        """Pick the ports and start every process but those named in ``hold`` (members
        that join late: :meth:`spawn` them; the mission starts when all are present)."""
        unknown = set(hold) - set(self.names) - set(self.pulses)
        if unknown:
            raise ValueError(f"no process {sorted(unknown)[0]!r} in this team")
        self.settings.record_dir.mkdir(parents=True, exist_ok=True)
        udp = self.settings.zenoh.protocol == "udp"
        if self.addresses is not None:
            self.ports = dict.fromkeys(self.names, 7447)  # one address each
        else:
            self.ports = {name: free_port(self.host, udp=udp) for name in self.names}
        for name in (*self.names, *self.pulses):
            if name not in hold:
                self.spawn(name)

    def spawn(self, name: str) -> Child:
        """Start (or restart) process ``name`` on its port."""
        if name not in self.names and name not in self.pulses:
            raise ValueError(f"no process {name!r} in this team")
        old = self.children.get(name)
        if old is not None and old.process.poll() is None:
            raise RuntimeError(f"{name} is still running")
        self.gone.pop(name, None)
        count = self.restarts.get(name, -1) + 1
        self.restarts[name] = count
        suffix = f".{count}" if count else ""
        log = self.settings.record_dir / f"{name}{suffix}.log"
        handle = log.open("wb")
        host = self.pulses.get(name, name)  # a pulse runs on its robot's host
        args = [*self.wrappers.get(host, []), sys.executable, "-c", _CLI, *self.command(name)]
        env = dict(os.environ)
        env.setdefault("PYTHONUNBUFFERED", "1")
        if name == OPERATOR_ID and self.settings.console_token is not None:
            env[CONSOLE_TOKEN_ENV] = self.settings.console_token
        if self.settings.base.kind == "nav2":
            # One host: ROS 2 discovery stays on it unless the user said otherwise.
            env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        # It dies with this process, however this one ends (leftovers.die_with_parent).
        process = subprocess.Popen(
            args, stdout=handle, stderr=subprocess.STDOUT, env=env, preexec_fn=die_with_parent()
        )
        child = Child(name, self.ports.get(name, 0), process, log, handle)
        self.children[name] = child
        return child

    def command(self, name: str) -> list[str]:
        """The ``mrcomm`` arguments that start process ``name``."""
        if name in self.pulses:
            return self.pulse_command(name)
        s = self.settings
        run = s.run
        proto = s.zenoh.protocol
        args = ["world" if name == WORLD_ID else "agent", str(run.scenario)]
        if name != WORLD_ID:
            args += ["--robot", name]
        args += [
            "--network", run.network,
            "--spl", f"{run.spl:g}",
            "--behaviour", run.behaviour,
            "--threshold", run.threshold,
            "--seed", str(run.seed),
            "--max-time", f"{run.max_time:g}",
            "--dt", f"{run.dt:g}",
            *(arg for item in param_assignments(run) for arg in ("--set", item)),
            "--team", s.zenoh.team,
            "--mission", str(s.mission),
            "--record-dir", str(s.record_dir),
            "--listen", f"{proto}/{self.address(name)}:{self.ports[name]}",
            "--link-lease", f"{s.zenoh.link_lease:g}",
        ]  # fmt: skip
        # The team's peers form one mesh; each agent reaches the world (its robot's
        # body) on a session of its own, so world traffic never shares team links.
        if name != WORLD_ID:
            for other in self.names:
                if other not in (name, WORLD_ID):
                    args += ["--connect", f"{proto}/{self.address(other)}:{self.ports[other]}"]
            world = f"{proto}/{self.address(WORLD_ID)}:{self.ports[WORLD_ID]}"
            args += ["--world-connect", world]
        if proto == "udp":
            args += ["--protocol", "udp"]
        if s.zenoh.multicast:
            args += ["--multicast"]
        nav2 = s.base.kind == "nav2"  # the robots' bases over ROS 2, served by the world
        if name == WORLD_ID:
            args += ["--speed", f"{s.speed:g}", "--start-timeout", f"{s.start_timeout:g}"]
            args += ["--ros2"] if nav2 else []
            args += ["--emulate", str(emulation_path(s))] if s.emulated else []
        else:
            args += ["--base", "nav2"] if nav2 and name in self.robots else []
            args += ["--emulated"] if s.emulated else []
            args += ["--join-timeout", f"{s.join_timeout:g}"]
            if s.lease is not None:
                args += ["--lease", f"{s.lease:g}"]
            if s.agent_clock != "shared":
                args += ["--clock", s.agent_clock]
            if name == OPERATOR_ID and s.operator is not None:
                args += ["--operator", str(s.operator)]
            if name == OPERATOR_ID and s.console_port is not None:
                args += ["--console", "--port", str(s.console_port)]
        args += self.security_args()
        return args + self.extra_args.get(name, [])

    def pulse_command(self, name: str) -> list[str]:
        """The ``mrcomm pulse`` arguments of a robot's trace-replaying pulse: it publishes
        to its robot's agent and hears the world's clock on a session of its own, with
        its robot's certificate (it runs on that robot)."""
        s = self.settings
        robot = self.pulses[name]
        proto = s.zenoh.protocol
        trace = pulse_trace_path(s.run)
        assert trace is not None
        args = [
            "pulse", "--trace", str(trace), "--robot", robot,
            "--team", s.zenoh.team,
            "--connect", f"{proto}/{self.address(robot)}:{self.ports[robot]}",
            "--world-connect", f"{proto}/{self.address(WORLD_ID)}:{self.ports[WORLD_ID]}",
            "--link-lease", f"{s.zenoh.link_lease:g}",
        ]  # fmt: skip
        if proto == "udp":
            args += ["--protocol", "udp"]
        args += self.security_args()  # a pulse presents its robot's certificate
        return args + self.extra_args.get(name, [])

    def security_args(self) -> list[str]:
        if self.team_dir is None:
            return ["--insecure"]
        return ["--team-dir", str(self.team_dir)]

    def address(self, name: str) -> str:
        return self.addresses[name] if self.addresses is not None else self.host

    def kill(self, name: str, sig: int = signal.SIGKILL) -> None:
        child = self.children[name]
        if child.process.poll() is None:
            child.process.send_signal(sig)
            child.process.wait(timeout=10)

    def running(self, name: str) -> bool:
        child = self.children.get(name)
        return child is not None and child.process.poll() is None

    # -- waiting -------------------------------------------------------------------------
    def mission_timeout(self) -> float:
        s = self.settings
        return s.start_timeout + s.run.max_time / s.speed + 60.0

    def wait(
        self, timeout: float | None = None, on_progress: Callable[[], None] | None = None
    ) -> None:
        """Wait for the world to end the mission and the agents to finish; a failed
        world (bad input, team never ready) raises its one-line error. ``on_progress``
        is called about every ``PROGRESS_PERIOD`` s of wall time meanwhile."""
        deadline = time.monotonic() + (timeout if timeout is not None else self.mission_timeout())
        world = self.children[WORLD_ID].process
        while True:
            left = deadline - time.monotonic()
            try:
                world.wait(timeout=max(min(left, PROGRESS_PERIOD), 0.01))
                break
            except subprocess.TimeoutExpired:
                if left <= PROGRESS_PERIOD:
                    self.stop()
                    message = "the live mission did not end in time (see the logs)"
                    raise MissionFailed(message) from None
                self._stop_if_team_dead()
                if on_progress is not None:
                    on_progress()
        if world.returncode != 0:
            self.stop()
            raise InputError(self.first_error() or f"world exited with status {world.returncode}")
        agents_deadline = time.monotonic() + EXIT_GRACE
        lingered: set[str] = set()
        for child in self.children.values():
            remaining = max(agents_deadline - time.monotonic(), 0.1)
            try:
                child.process.wait(timeout=remaining)
            except subprocess.TimeoutExpired:
                lingered.add(child.name)
                child.process.terminate()
                try:
                    child.process.wait(timeout=10)
                except subprocess.TimeoutExpired:  # stuck closing its links: as stop() does
                    child.process.kill()
                    child.process.wait()
        self.died = [
            self.death(child)
            for child in self.children.values()
            if child.name not in lingered and child.process.returncode not in (0, None)
        ]

    def _stop_if_team_dead(self) -> None:
        """Every agent process (robots, task assigner, operator) has died while the
        world still runs: no one is left to end the mission, so stop now instead of
        waiting out its time limit, naming the first to die and its log. (An agent that
        exits cleanly has seen the end of the mission: the world is ending too.)"""
        agents = [self.children.get(name) for name in self.names if name != WORLD_ID]
        for child in agents:
            if child is not None and child.process.poll() not in (None, 0):
                self.gone.setdefault(child.name, time.monotonic())
        if not agents or any(c is None or c.name not in self.gone for c in agents):
            return
        dead = [c for c in agents if c is not None]
        first = min(dead, key=lambda c: self.gone[c.name])
        line = self.death(first)
        self.stop()
        raise MissionFailed(
            f"every agent process has died ({len(dead)}); the first: {line} (its log: {first.log})"
        )

    def death(self, child: Child) -> str:
        """One line on a process that died: how, and the first line of its error."""
        code = child.process.returncode
        how = f"killed by signal {-code}" if code < 0 else f"exited with status {code}"
        if not child.handle.closed:
            child.handle.flush()
        lines = child.log.read_text(errors="replace").splitlines()
        said = next((line for line in lines if line.startswith("mrcomm: error:")), "")
        said = said.removeprefix("mrcomm: error:").strip()
        if not said and any(line.startswith("Traceback") for line in lines):
            # The last line of a traceback says what was raised.
            said = next(line for line in reversed(lines) if line and not line[0].isspace())
        return f"{child.name} {how}" + (f": {said}" if said else "")

    def first_error(self) -> str | None:
        """The first one-line error any process printed (``name: message``)."""
        for name, child in self.children.items():
            if not child.handle.closed:
                child.handle.flush()
            for line in child.log.read_text(errors="replace").splitlines():
                if line.startswith("mrcomm: error:"):
                    return f"{name}: {line.removeprefix('mrcomm: error:').strip()}"
        return None

    def stop(self) -> None:
        for child in self.children.values():
            if child.process.poll() is None:
                child.process.terminate()
        for child in self.children.values():
            try:
                child.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                child.process.kill()
                child.process.wait()
            child.handle.close()

    def collect(self) -> tuple[MissionResult, dict[str, Any]]:
        """The run's result and live report; the report's ``died`` lists the processes
        that died during the mission (one line each)."""
        result, report = collect(self.settings.record_dir)
        report["died"] = list(self.died)
        return result, report

    def __enter__(self) -> LiveTeam:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


#: Where :func:`free_port` looks: above the well-known and common service ports and
#: below the kernel's ephemeral range (read from Linux, 32768 by default).
_LOWEST_PORT = 20000
_EPHEMERAL_RANGE = Path("/proc/sys/net/ipv4/ip_local_port_range")


def free_port(host: str, *, udp: bool = False) -> int:
    """A port nobody listens on right now, chosen below the kernel's ephemeral range.

    Why not bind port 0 and release it: the kernel hands out the same range to every
    socket that connects without binding, and a process takes a second or more to start
    and listen. Over UDP, where every Zenoh link opens such a socket, another one could
    take the port in that second and the process would listen on a port whose packets
    go elsewhere. Ports below the ephemeral range are only ever taken by an explicit
    bind; picking one at random makes two launchers (parallel tests) unlikely to meet."""
    kind = socket.SOCK_DGRAM if udp else socket.SOCK_STREAM
    try:
        ephemeral_low = int(_EPHEMERAL_RANGE.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        ephemeral_low = 32768  # Linux's default; elsewhere the range is not readable
    pick = random.SystemRandom()  # not the run's seed: a port is not part of a result
    for _ in range(200):
        port = pick.randrange(_LOWEST_PORT, max(ephemeral_low, _LOWEST_PORT + 1000))
        with socket.socket(socket.AF_INET, kind) as sock:
            try:
                sock.bind((host, port))
            except OSError:
                continue
            return port
    with socket.socket(socket.AF_INET, kind) as sock:  # crowded: let the OS choose
        sock.bind((host, 0))
        return int(sock.getsockname()[1])


def run_live(
    settings: LiveSettings,
    *,
    team_dir: Path | None = None,
    on_progress: Callable[[], None] | None = None,
    extra_args: dict[str, list[str]] | None = None,
) -> tuple[MissionResult, dict[str, Any]]:
    """Launch, wait for the end of the mission, collect: the live ``mrcomm run``. Any
    exception (Ctrl-C too) stops every process first. ``extra_args``: more command-line
    arguments per process (e.g. the world's ``--foxglove``)."""
    if settings.emulated:
        return _run_emulated(settings, team_dir, on_progress, extra_args)
    with LiveTeam(settings, team_dir=team_dir, extra_args=extra_args) as team:
        team.start()
        team.wait(on_progress=on_progress)
        return team.collect()


def emulation_path(settings: LiveSettings) -> Path:
    return settings.record_dir / "emulation.json"


def _run_emulated(
    settings: LiveSettings,
    team_dir: Path | None,
    on_progress: Callable[[], None] | None,
    extra_args: dict[str, list[str]] | None,
) -> tuple[MissionResult, dict[str, Any]]:
    """The team in network namespaces (``live.netns``), one per process, the world
    told where every link node is (``live.kernel_links``)."""
    names = LiveTeam(settings, team_dir=team_dir).names
    scenario = load_scenario(settings.run.scenario)
    remove_stale_namespaces()  # of an emulated run killed before it could remove them
    with Netns(names, spared=(WORLD_ID,)) as net:
        addresses = {r.id: net.ip[r.id] for r in scenario.robots}
        host = scenario.assigner.host if scenario.assigner.kind == "robot" else ASSIGNER_ID
        addresses[ASSIGNER_ID] = net.ip[host or ASSIGNER_ID]
        settings.record_dir.mkdir(parents=True, exist_ok=True)
        Emulation(net.hub, addresses).write(emulation_path(settings))
        wrappers = {name: net.wrapper(name) for name in names}
        with LiveTeam(
            settings, team_dir=team_dir, extra_args=extra_args, addresses=net.ip,
            wrappers=wrappers,
        ) as team:  # fmt: skip
            team.start()
            team.wait(on_progress=on_progress)
            return team.collect()
