"""``mrcomm world`` / ``agent`` / ``live`` / ``collect``: the live mode's commands.

* ``mrcomm world SCENARIO`` — simulates every robot's base, publishes the clock;
* ``mrcomm agent SCENARIO --robot ID`` — one agent process (hosts the task assigner
  when the scenario puts it on this robot; ``--robot assigner`` runs a stand-alone one);
* ``mrcomm live SCENARIO`` — world and every agent as processes on this host, then the
  same tables / JSON as ``mrcomm run``;
* ``mrcomm collect RECORD_DIR`` — merge the records of a live run.

Every process takes the same run options as ``mrcomm run`` plus how to join the
team's Zenoh network; bad input is a one-line error with exit status 2.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from mrcomm.cli.db_option import DbOpt, ExperimentOpt, KeepDuplicateOpt, check_db, store_run
from mrcomm.cli.live_display import LiveDisplay
from mrcomm.cli.run_cmd import show_result
from mrcomm.cli.run_options import warn_ignored_settings, with_run_options
from mrcomm.errors import InputError, Interrupted
from mrcomm.net.zenoh_config import ZenohOptions, make_options

if TYPE_CHECKING:
    from mrcomm.run.config import RunConfig

TeamOpt = Annotated[str, typer.Option(help="Team name: the key space mrcomm/<team>/.")]
ListenOpt = Annotated[
    list[str] | None, typer.Option("--listen", help="Endpoint to listen on (repeatable).")
]
ConnectOpt = Annotated[
    list[str] | None, typer.Option("--connect", help="Peer endpoint to connect to (repeatable).")
]
MulticastOpt = Annotated[
    bool, typer.Option("--multicast/--no-multicast", help="Multicast scouting for peers.")
]
ProtocolOpt = Annotated[str, typer.Option(help="Transport: tcp | udp.")]
TlsCaOpt = Annotated[Path | None, typer.Option(help="Team CA certificate (PEM): enables mTLS.")]
TlsCertOpt = Annotated[Path | None, typer.Option(help="This node's certificate (PEM).")]
TlsKeyOpt = Annotated[Path | None, typer.Option(help="This node's private key (PEM).")]
AclOpt = Annotated[
    str | None,
    typer.Option(help="Comma-separated certificate names allowed on the team's keys (ACL)."),
]
ZenohConfigOpt = Annotated[Path | None, typer.Option(help="Zenoh JSON5 config file.")]
LinkLeaseOpt = Annotated[float, typer.Option(help="Zenoh link lease, wall s.")]
RecordDirOpt = Annotated[Path, typer.Option(help="Directory of this run's records.")]
SpeedOpt = Annotated[float, typer.Option(help="Simulated seconds per wall-clock second.")]
LeaseOpt = Annotated[
    float | None, typer.Option(help="AON lease, simulated s: silent members are left out.")
]


def zenoh_options(
    team: str,
    listen: list[str] | None,
    connect: list[str] | None,
    multicast: bool,
    protocol: str,
    tls_ca: Path | None,
    tls_cert: Path | None,
    tls_key: Path | None,
    acl: str | None,
    zenoh_config: Path | None,
    link_lease: float,
) -> ZenohOptions:
    """The Zenoh options of a live process (world, agent, pulse) from its command line."""
    members = [m.strip() for m in acl.split(",") if m.strip()] if acl is not None else None
    return make_options(
        team=team,
        listen=listen or [],
        connect=connect or [],
        multicast=multicast,
        protocol=protocol,
        tls_ca=tls_ca,
        tls_cert=tls_cert,
        tls_key=tls_key,
        acl_members=members,
        config_file=zenoh_config,
        link_lease=link_lease,
    )


@with_run_options
def world(
    run: RunConfig,
    speed: SpeedOpt = 1.0,
    team: TeamOpt = "team",
    listen: ListenOpt = None,
    connect: ConnectOpt = None,
    multicast: MulticastOpt = False,
    protocol: ProtocolOpt = "tcp",
    tls_ca: TlsCaOpt = None,
    tls_cert: TlsCertOpt = None,
    tls_key: TlsKeyOpt = None,
    acl: AclOpt = None,
    zenoh_config: ZenohConfigOpt = None,
    link_lease: LinkLeaseOpt = 10.0,
    record_dir: RecordDirOpt = Path("live-records"),
    start_timeout: Annotated[
        float, typer.Option(help="Wall s to wait for every agent to be ready.")
    ] = 60.0,
) -> None:
    """Simulate every robot's base and publish the shared clock (live mode)."""
    run.check_mode("live")
    from mrcomm.live.settings import LiveSettings
    from mrcomm.live.world import run_world

    zenoh = zenoh_options(
        team, listen, connect, multicast, protocol, tls_ca, tls_cert, tls_key, acl,
        zenoh_config, link_lease,
    )  # fmt: skip
    settings = LiveSettings(
        run, zenoh, record_dir.expanduser(), speed=speed, start_timeout=start_timeout
    ).with_record_dir()
    raise typer.Exit(run_world(settings))


@with_run_options
def agent(
    run: RunConfig,
    robot: Annotated[str, typer.Option(help="Robot id of this agent (or 'assigner').")],
    team: TeamOpt = "team",
    listen: ListenOpt = None,
    connect: ConnectOpt = None,
    multicast: MulticastOpt = False,
    protocol: ProtocolOpt = "tcp",
    tls_ca: TlsCaOpt = None,
    tls_cert: TlsCertOpt = None,
    tls_key: TlsKeyOpt = None,
    acl: AclOpt = None,
    zenoh_config: ZenohConfigOpt = None,
    link_lease: LinkLeaseOpt = 10.0,
    record_dir: RecordDirOpt = Path("live-records"),
    lease: LeaseOpt = None,
    world_connect: Annotated[
        list[str] | None,
        typer.Option(
            "--world-connect",
            help="The world's endpoint, on a session of its own (repeatable; default: "
            "the world is reached over the team's session).",
        ),
    ] = None,
    join_timeout: Annotated[
        float, typer.Option(help="Wall s to reach the team before giving up.")
    ] = 20.0,
    clock: Annotated[
        str,
        typer.Option(
            help="What steps the agent: shared (the world's ticks) | host (every --dt "
            "on this host's monotonic clock from the first tick; the world at --speed 1)."
        ),
    ] = "shared",
) -> None:
    """Run one robot's agent (task executor, and the assigner it hosts) over Zenoh."""
    run.check_mode("live")
    from mrcomm.live.agent import check_agent_id, run_agent
    from mrcomm.live.settings import LiveSettings, check_agent_clock
    from mrcomm.world.scenario import load_scenario

    check_agent_clock(clock, "--clock")
    check_agent_id(load_scenario(run.scenario), robot)
    zenoh = zenoh_options(
        team, listen, connect, multicast, protocol, tls_ca, tls_cert, tls_key, acl,
        zenoh_config, link_lease,
    )  # fmt: skip
    world_options = None
    if world_connect:
        world_options = zenoh_options(
            team, None, world_connect, False, protocol, tls_ca, tls_cert, tls_key, acl,
            None, link_lease,
        )  # fmt: skip
    settings = LiveSettings(
        run,
        zenoh,
        record_dir.expanduser(),
        world=world_options,
        lease=lease,
        join_timeout=join_timeout,
        agent_clock=clock,
    ).with_record_dir()
    raise typer.Exit(run_agent(settings, robot))


@with_run_options
def live(
    run: RunConfig,
    speed: SpeedOpt = 1.0,
    team: TeamOpt = "team",
    protocol: ProtocolOpt = "tcp",
    tls_dir: Annotated[
        Path | None,
        typer.Option(help="Team certificates: ca.pem, <process>.pem / .key (enables mTLS)."),
    ] = None,
    acl: Annotated[bool, typer.Option("--acl", help="With --tls-dir: team-only ACL.")] = False,
    lease: LeaseOpt = None,
    record_dir: Annotated[
        Path | None, typer.Option(help="Keep the records here (default: a temporary dir).")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    db: DbOpt = None,
    experiment: ExperimentOpt = None,
    keep_duplicate: KeepDuplicateOpt = False,
    agent_clock: Annotated[
        str,
        typer.Option(
            help="What steps the agents: shared (the world's ticks) | host (each its "
            "host's monotonic clock, as on real robots; needs --speed 1)."
        ),
    ] = "shared",
) -> None:
    """Run one mission live: world and every agent as separate processes over Zenoh;
    with --db, store it in a results database (mode live)."""
    run.check_mode("live")
    from mrcomm.live.collect import live_summary
    from mrcomm.live.launcher import TlsLayout, run_live
    from mrcomm.live.settings import (
        LiveSettings,
        check_agent_clock,
        check_positive,
        check_record_dir,
    )

    check_agent_clock(agent_clock, "--agent-clock", speed)
    if tls_dir is not None and not (tls_dir / "ca.pem").is_file():
        raise InputError("no ca.pem in the TLS directory", file=tls_dir, field="--tls-dir")
    if acl and tls_dir is None:
        raise InputError("the ACL identifies members by certificate: add --tls-dir", field="--acl")
    check_db(db, experiment)  # before any process is launched
    check_positive(speed, "--speed")  # before the record directory is made
    if lease is not None:
        check_positive(lease, "--lease")
    zenoh = make_options(team=team, protocol=protocol)
    directory = (
        check_record_dir(record_dir)
        if record_dir is not None
        else Path(tempfile.mkdtemp(prefix="mrcomm-live-"))
    )
    if tls_dir is not None:
        zenoh = ZenohOptions(team=zenoh.team, protocol="tls")
    settings = LiveSettings(
        run, zenoh, directory, speed=speed, lease=lease, agent_clock=agent_clock
    )
    tls = TlsLayout(tls_dir, acl=acl) if tls_dir is not None else None
    from mrcomm.world.scenario import load_scenario

    scenario = load_scenario(run.scenario)
    warn_ignored_settings(run)
    display = LiveDisplay(directory, run.max_time, len(scenario.tasks), len(scenario.robots))
    try:
        with display:
            result, report = run_live(settings, tls=tls, on_progress=display.update)
    except InputError:
        # A process refused its input (its one line is the error): nothing was run, so
        # no records are worth keeping in a temporary directory.
        if record_dir is None:
            shutil.rmtree(directory, ignore_errors=True)
        raise
    except KeyboardInterrupt:
        if record_dir is None:
            shutil.rmtree(directory, ignore_errors=True)
            raise Interrupted(
                "interrupted; every process stopped, the partial records removed"
            ) from None
        raise Interrupted(
            f"interrupted; every process stopped, the partial records kept in {directory}"
        ) from None
    live_options = {
        "speed": speed,
        "lease": lease,
        "protocol": protocol if tls_dir is None else "tcp",  # --tls-dir implies TLS
        "tls_dir": tls_dir,
        "acl": acl,
        "agent_clock": agent_clock,
    }
    stored = store_run(
        db,
        experiment,
        result,
        live_options=live_options,
        run_fingerprint=report["record_fingerprint"],
        keep_duplicate=keep_duplicate,
        if_lost=f"the records stay in {directory}: store them with mrcomm collect "
        f"{directory} --db ...",
    )
    latency = report.get("pose_latency_ms", {})
    footer = (
        f"live: records in {directory}; pose latency p50 {latency.get('p50', '-')} ms, "
        f"p99 {latency.get('p99', '-')} ms"
    )
    show_result(result, live_summary(result, report), stored, as_json, footer)
    if report["died"]:
        # The mission ran on without it: its result is shown and stored, but it is not
        # the run that was asked for.
        typer.echo(f"mrcomm: error: {report['died'][0]}", err=True)
        raise typer.Exit(1)


def collect_cmd(
    record_dir: Annotated[Path, typer.Argument(help="Record directory of a live run.")],
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    db: DbOpt = None,
    experiment: ExperimentOpt = None,
    keep_duplicate: KeepDuplicateOpt = False,
) -> None:
    """Merge the records every process of a live run wrote into one result; with --db,
    store it in a results database (mode live)."""
    from mrcomm.live.collect import collect, live_summary

    check_db(db, experiment)
    result, report = collect(record_dir)
    # The record says how its agents were clocked (the other live options it cannot).
    host = any(p["host_clock"] for p in report["processes"].values())
    stored = store_run(
        db,
        experiment,
        result,
        live_options={"agent_clock": "host"} if host else {},
        run_fingerprint=report["record_fingerprint"],
        keep_duplicate=keep_duplicate,
    )
    show_result(result, live_summary(result, report), stored, as_json)
