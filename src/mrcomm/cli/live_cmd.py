"""``mrcomm live`` / ``collect``: the live mode's commands, and the options its
processes share (``mrcomm world`` / ``agent``: ``process_cmd``).

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
from mrcomm.cli.zenoh_cli import InsecureOpt, ProtocolOpt, TeamOpt, warn_insecure
from mrcomm.errors import InputError, Interrupted
from mrcomm.net.zenoh_config import make_options

if TYPE_CHECKING:
    from mrcomm.run.config import RunConfig

RecordDirOpt = Annotated[Path, typer.Option(help="Directory of this run's records.")]
SpeedOpt = Annotated[float, typer.Option(help="Simulated seconds per wall-clock second.")]
BaseOpt = Annotated[
    str,
    typer.Option(
        help="The robot's base: native (the world's simulated base over Zenoh) | nav2 "
        "(a Nav2 robot over ROS 2; needs mrcomm[ros2], docs/PHYSICAL.md)."
    ),
]
LeaseOpt = Annotated[
    float | None, typer.Option(help="AON lease, simulated s: silent members are left out.")
]


@with_run_options
def live(
    run: RunConfig,
    speed: SpeedOpt = 1.0,
    team: TeamOpt = "team",
    protocol: ProtocolOpt = "tcp",
    team_dir: Annotated[
        Path | None,
        typer.Option(
            "--team-dir",
            help="Team directory (mrcomm team init) with a certificate for every "
            "process; default: a throwaway team made for this run.",
        ),
    ] = None,
    insecure: InsecureOpt = False,
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
    operator: Annotated[
        Path | None,
        typer.Option(
            help="An operator in the loop: its own process, with the task assigner, "
            "sending the file's commands (README)."
        ),
    ] = None,
    console: Annotated[
        bool,
        typer.Option(
            "--console",
            help="The operator console on http://localhost:--port, served by the "
            "operator's process (a team member; needs mrcomm[console]).",
        ),
    ] = False,
    foxglove: Annotated[
        bool,
        typer.Option(
            "--foxglove",
            help="The world streams the ground truth live to the Foxglove app on --foxglove-port.",
        ),
    ] = False,
    foxglove_port: Annotated[
        int, typer.Option(min=1, max=65535, help="Port of the --foxglove server.")
    ] = 8765,
    port: Annotated[int, typer.Option(min=1, max=65535, help="Port of the --console page.")] = (
        8080
    ),
    base: Annotated[
        str,
        typer.Option(
            help="native | nav2: every agent drives its robot through ROS 2 Nav2 "
            "interfaces, served by the world (mrcomm world --ros2; needs mrcomm[ros2])."
        ),
    ] = "native",
    emulate: Annotated[
        bool,
        typer.Option(
            "--emulate",
            help="Every process in its own network namespace; the world sets each pair's "
            "kernel packet drops from the network model (range, SPL) at 2 Hz and the "
            "agents filter nothing themselves (needs root, ip and nft).",
        ),
    ] = False,
) -> None:
    """Run one mission live: world and every agent as separate processes over Zenoh;
    with --db, store it in a results database (mode live)."""
    run.check_mode("live")
    from mrcomm.live.settings import BaseOptions

    base_options = BaseOptions(base)
    if base_options.kind == "nav2":
        from mrcomm.ros2.runtime import need_ros2

        need_ros2("--base")  # before any process
    if emulate:
        check_emulation(run, operator is not None or console)
    from mrcomm.live.collect import live_summary
    from mrcomm.live.identity import check_team_members, live_members, throwaway_team
    from mrcomm.live.launcher import run_live
    from mrcomm.live.settings import (
        LiveSettings,
        check_agent_clock,
        check_positive,
        check_record_dir,
    )

    check_agent_clock(agent_clock, "--agent-clock", speed)
    check_db(db, experiment)  # before any process is launched
    check_positive(speed, "--speed")  # before the record directory is made
    if lease is not None:
        check_positive(lease, "--lease")
    zenoh = make_options(team=team, protocol=protocol)
    from mrcomm.run.resources import checked_scenario

    scenario = checked_scenario(run.scenario)
    refusal = run.spec("network").load().live_refusal(run.variant_params("network"))
    if refusal is not None:
        raise InputError(refusal, field="network.channel")
    members = live_members(scenario)
    if operator is not None:
        from mrcomm.run.operator_plan import load_operator_plan

        reassignable = run.spec("behaviour").accepts_reassignment
        load_operator_plan(operator, scenario, reassignable=reassignable)  # before any process
        operator = operator.resolve()
    if console:
        from mrcomm.cli.console_cmd import need_console_extra

        need_console_extra("--console")  # before any process
    if operator is not None or console:
        from mrcomm.agents.commands import OPERATOR_ID

        members = (*members, OPERATOR_ID)
    if team_dir is not None:
        if insecure:
            raise InputError("--insecure contradicts --team-dir", field="--insecure")
        check_team_members(team_dir, members)
    elif not insecure and protocol == "udp":
        raise InputError(
            "a live team talks TLS (over TCP) unless --insecure: drop --protocol udp",
            field="--protocol",
        )
    directory = (
        check_record_dir(record_dir)
        if record_dir is not None
        else Path(tempfile.mkdtemp(prefix="mrcomm-live-"))
    )
    guard = None
    if console:
        from mrcomm.console.guard import ConsoleGuard

        guard = ConsoleGuard(port)
    settings = LiveSettings(
        run, zenoh, directory, speed=speed, lease=lease, agent_clock=agent_clock,
        operator=operator, console_port=port if console else None, base=base_options,
        emulated=emulate, console_token=guard.token if guard is not None else None,
    )  # fmt: skip
    warn_ignored_settings(run)
    warn_insecure(insecure)
    if guard is not None:
        typer.echo(f"console: {guard.url}", err=True)
    display = LiveDisplay(directory, run.max_time, len(scenario.tasks), len(scenario.robots))
    try:
        with display, throwaway_team(team_dir, insecure, members) as used_dir:
            world_args = ["--foxglove", "--foxglove-port", str(foxglove_port)]
            extra = {"world": world_args}  # the world process streams its ground truth
            result, report = run_live(
                settings, team_dir=used_dir, on_progress=display.update,
                extra_args=extra if foxglove else None,
            )  # fmt: skip
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
        "protocol": protocol,
        "team_dir": team_dir,
        "insecure": insecure,
        "agent_clock": agent_clock,
        "base": base,
        "emulate": emulate,
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


def check_emulation(run: RunConfig, operator: bool) -> None:
    """What ``--emulate`` can do here, checked before any process (one line, exit 2)."""
    from mrcomm.live.netns import netns_missing

    if operator:
        raise InputError("an operator cannot join an emulated team yet", field="--emulate")
    missing = netns_missing()
    if missing is not None:
        raise InputError(missing, field="--emulate")


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
