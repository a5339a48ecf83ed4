"""Settings shared by the live processes (world, agents, launcher): the run's
configuration (the same model as ``mrcomm run``), how to join the Zenoh network,
where to record, and the live-only knobs (speed, AON lease, time-outs, the agents'
clock)."""

from __future__ import annotations

import json
import math
import zlib
from dataclasses import dataclass
from pathlib import Path

from mrcomm.errors import InputError, did_you_mean
from mrcomm.net.zenoh_config import ZenohOptions
from mrcomm.run.config import RunConfig

#: What steps an agent: the world's ticks (``shared``, as Stage's ``use_sim_time``) or
#: its own host's monotonic clock (``host``, as on a real robot; ``live.host_clock``).
AGENT_CLOCKS = ("shared", "host")
#: What an agent drives: the world's simulated base over Zenoh (``native``), or a
#: robot's Nav2 stack over ROS 2 (``nav2``: a real robot, or ``mrcomm world --ros2``).
BASES = ("native", "nav2")


def mission_bytes(text: str) -> bytes:
    """The 8 bytes of a mission identity given as 16 hex digits (``--mission``)."""
    try:
        value = bytes.fromhex(text)
    except ValueError:
        value = b""
    if len(value) != 8 or value == bytes(8):
        raise InputError(
            f"a mission identity is 16 hex digits, not all zero; got {text[:40]!r}",
            field="--mission",
        )
    return value


#: The environment variable that carries the console's secret to the operator's process.
CONSOLE_TOKEN_ENV = "MRCOMM_CONSOLE_TOKEN"


@dataclass(frozen=True)
class BaseOptions:
    """An agent's robot base and, for ``nav2``, its ROS names (``ros2.runtime``)."""

    kind: str = "native"
    #: ROS namespace of the robot's Nav2 interfaces; None: ``/<robot id>``.
    namespace: str | None = None
    frame: str = "map"
    qos: str = "best_effort"

    def __post_init__(self) -> None:
        if self.kind not in BASES:
            hint = did_you_mean(self.kind, BASES)
            message = f"unknown base {self.kind!r}{hint}; choose native or nav2"
            raise InputError(message, field="--base")


@dataclass(frozen=True)
class LiveSettings:
    run: RunConfig
    zenoh: ZenohOptions
    record_dir: Path
    #: An agent's separate session to the world process (the stand-in for its robot's
    #: body, local on a real robot): clock and base traffic then never share the team's
    #: emulated network. None: one session for everything.
    world: ZenohOptions | None = None
    #: Simulated seconds per wall-clock second (the world's pace).
    speed: float = 1.0
    #: AON lease (simulated s): a member silent this long is reported left out.
    lease: float | None = None
    #: Wall seconds an agent waits to reach the team (the world) before giving up.
    join_timeout: float = 20.0
    #: Wall seconds the world waits for every agent to be ready.
    start_timeout: float = 60.0
    #: One of :data:`AGENT_CLOCKS`; ``host`` needs ``speed`` 1 (host time is real time).
    agent_clock: str = "shared"
    #: An operator in the loop: the operator file (its process: ``--robot operator``).
    operator: Path | None = None
    #: Serve the operator console on this port (from the operator's process).
    console_port: int | None = None
    #: The mission's identity (16 hex digits; the world draws one when it is None, and
    #: an agent without one adopts the world's): every message carries it, and one of
    #: another mission is refused.
    mission: str | None = None
    #: The console's per-run secret (the launcher hands it to the operator's process
    #: in :data:`CONSOLE_TOKEN_ENV`, never on a command line other users can read).
    console_token: str | None = None
    #: The robots' bases: the world's simulated ones over Zenoh, or Nav2 over ROS 2.
    base: BaseOptions = BaseOptions()
    #: Agents: the kernel applies the network model (``--emulate``), so their buses
    #: filter nothing. Launcher: run the team in network namespaces with kernel links.
    emulated: bool = False

    @property
    def has_operator(self) -> bool:
        return self.operator is not None or self.console_port is not None

    def __post_init__(self) -> None:
        if self.mission is not None:
            mission_bytes(self.mission)  # a one-line error for a bad one
        check_positive(self.speed, "--speed")
        if self.lease is not None:
            check_positive(self.lease, "--lease")
        check_positive(self.join_timeout, "--join-timeout")
        check_positive(self.start_timeout, "--start-timeout")
        check_agent_clock(self.agent_clock, "--agent-clock", self.speed)

    def with_record_dir(self) -> LiveSettings:
        """The settings, their record directory created (after every other check, so
        that bad input leaves nothing behind)."""
        check_record_dir(self.record_dir)
        return self


def check_positive(value: float, option: str) -> float:
    """A finite, positive number (NaN and infinity are refused in one line)."""
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"must be a finite positive number, got {value:g}", field=option)
    return value


def check_agent_clock(clock: str, option: str, speed: float = 1.0) -> str:
    """``clock`` must be one of :data:`AGENT_CLOCKS`; a host clock runs in real seconds,
    so the world (``speed``) must too."""
    if clock not in AGENT_CLOCKS:
        hint = did_you_mean(clock, AGENT_CLOCKS)
        raise InputError(f"unknown clock {clock!r}{hint}; choose shared or host", field=option)
    if clock == "host" and speed != 1.0:
        raise InputError(
            f"agents on their host's clock step in real seconds: needs --speed 1, not {speed:g}",
            field=option,
        )
    return clock


def config_crc(run: RunConfig) -> int:
    """Fingerprint of what the team must agree on (every process gets the same run
    options; a mismatch would silently change the experiment)."""
    data = run.model_dump(mode="json")
    # Files by name: each host may keep its copy elsewhere.
    data["scenario"] = Path(str(data["scenario"])).name
    if data.get("rssi_trace") is not None:
        data["rssi_trace"] = Path(str(data["rssi_trace"])).name
    return zlib.crc32(json.dumps(data, sort_keys=True).encode())


def check_record_dir(path: Path) -> Path:
    path = path.expanduser()
    if path.exists() and not path.is_dir():
        raise InputError("not a directory", file=path, field="--record-dir")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        message = f"cannot create: {err.strerror}"
        raise InputError(message, file=path, field="--record-dir") from None
    return path
