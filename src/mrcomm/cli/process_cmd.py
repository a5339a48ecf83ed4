"""``mrcomm world`` / ``mrcomm agent``: the live mode's processes one at a time (what
``mrcomm live`` starts for you, and what runs on each host of a team spread over
machines; on a robot ``mrcomm agent --base nav2`` drives its Nav2 stack).

* ``mrcomm world SCENARIO`` — simulates every robot's base, publishes the clock; with
  ``--ros2`` also serves the robots as Nav2 robots over ROS 2, with ``--emulate FILE``
  sets the team's kernel packet drops from the network model;
* ``mrcomm agent SCENARIO --robot ID`` — one agent process (hosts the task assigner
  when the scenario puts it on this robot; ``--robot assigner`` runs a stand-alone one).

Their Zenoh and security options are ``live_cmd``'s; bad input is a one-line error
with exit status 2.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from mrcomm.cli.live_cmd import BaseOpt, LeaseOpt, RecordDirOpt, SpeedOpt
from mrcomm.cli.run_options import with_run_options
from mrcomm.cli.zenoh_cli import warn_insecure, with_zenoh_options
from mrcomm.errors import InputError

if TYPE_CHECKING:
    from mrcomm.cli.zenoh_cli import ZenohCli
    from mrcomm.run.config import RunConfig


MissionOpt = Annotated[
    str | None,
    typer.Option(
        help="The mission's identity (16 hex digits; mrcomm live draws one): messages of "
        "another mission are refused. The world draws one when none is given; an agent "
        "without one adopts the world's."
    ),
]


@with_run_options
@with_zenoh_options
def world(
    run: RunConfig,
    net: ZenohCli,
    speed: SpeedOpt = 1.0,
    mission: MissionOpt = None,
    record_dir: RecordDirOpt = Path("live-records"),
    start_timeout: Annotated[
        float, typer.Option(help="Wall s to wait for every agent to be ready.")
    ] = 60.0,
    foxglove: Annotated[
        bool,
        typer.Option(
            "--foxglove",
            help="Stream the ground truth (map, robots, links) live to the Foxglove app "
            "on --foxglove-port.",
        ),
    ] = False,
    foxglove_port: Annotated[
        int, typer.Option(min=0, max=65535, help="Port of the --foxglove server.")
    ] = 8765,
    ros2: Annotated[
        bool,
        typer.Option(
            "--ros2",
            help="Also serve every robot as a Nav2 robot over ROS 2 (NavigateToPose, "
            "amcl_pose, odom in /<robot id>), for agents run with --base nav2; needs "
            "mrcomm[ros2].",
        ),
    ] = False,
    emulate: Annotated[
        Path | None,
        typer.Option(
            help="Emulation file (written by mrcomm live --emulate): set the per-pair "
            "kernel packet drops of the team's namespaces from the network model."
        ),
    ] = None,
) -> None:
    """Simulate every robot's base and publish the shared clock (live mode)."""
    run.check_mode("live")
    if ros2:
        from mrcomm.ros2.runtime import need_ros2

        need_ros2("--ros2")
    emulation = None
    if emulate is not None:
        from mrcomm.live.kernel_links import Emulation

        emulation = Emulation.read(emulate)
    from mrcomm.live.protocol import WORLD_ID
    from mrcomm.live.settings import LiveSettings
    from mrcomm.live.world import run_world
    from mrcomm.world.scenario import load_scenario

    security = net.security(WORLD_ID, load_scenario(run.scenario))
    zenoh = net.options(security)
    settings = LiveSettings(
        run, zenoh, record_dir.expanduser(), speed=speed, start_timeout=start_timeout,
        mission=mission,
    ).with_record_dir()  # fmt: skip
    warn_insecure(net.insecure)
    if not foxglove and not ros2 and emulation is None:
        raise typer.Exit(run_world(settings))
    from mrcomm.live.journal import new_incarnation
    from mrcomm.live.world import WorldProcess

    process = WorldProcess(settings, new_incarnation(settings.record_dir, WORLD_ID))
    if ros2:
        from mrcomm.ros2.nav2_server import Nav2Server

        process.base_server = Nav2Server(process.robot_ids)
    if emulation is not None:
        from mrcomm.live.kernel_links import KernelLinks

        process.kernel_links = KernelLinks(
            emulation, run.spl, process.journal.write, packet_error=radio_packet_error(process)
        )
    if not foxglove:
        raise typer.Exit(process.run())
    from mrcomm.experiment.recording import GroundTruthStream

    scenario = process.resources.scenario
    stream = GroundTruthStream(scenario.grid, process.robot_ids, scenario.robot_radius)
    port = stream.serve("127.0.0.1", foxglove_port)
    typer.echo(f"Foxglove: open ws://localhost:{port} in the Foxglove app", err=True)
    process.on_record = stream
    try:
        status = process.run()
    finally:
        stream.close()
    raise typer.Exit(status)


@with_run_options
@with_zenoh_options
def agent(
    run: RunConfig,
    robot: Annotated[str, typer.Option(help="Robot id of this agent (or 'assigner').")],
    net: ZenohCli,
    mission: MissionOpt = None,
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
    operator: Annotated[
        Path | None,
        typer.Option(help="With --robot operator: the operator file (its commands)."),
    ] = None,
    console: Annotated[
        bool,
        typer.Option(
            "--console",
            help="With --robot operator: serve the operator console on --port "
            "(http://localhost; needs mrcomm[console]).",
        ),
    ] = False,
    port: Annotated[int, typer.Option(min=1, max=65535, help="Port of the --console page.")] = (
        8080
    ),
    emulated: Annotated[
        bool,
        typer.Option(
            "--emulated",
            help="The kernel applies the network model to this agent's traffic (mrcomm "
            "live --emulate): its bus filters nothing.",
        ),
    ] = False,
    base: BaseOpt = "native",
    ros_namespace: Annotated[
        str | None,
        typer.Option(help="With --base nav2: the robot's ROS namespace (default /<robot id>)."),
    ] = None,
    ros_frame: Annotated[
        str, typer.Option(help="With --base nav2: the map frame of goals and poses.")
    ] = "map",
    ros_qos: Annotated[
        str,
        typer.Option(
            help="With --base nav2: reliability of the pose and odometry subscriptions "
            "(best_effort matches any publisher | reliable)."
        ),
    ] = "best_effort",
) -> None:
    """Run one robot's agent (task executor, and the assigner it hosts) over Zenoh."""
    run.check_mode("live")
    from mrcomm.live.agent import check_agent_id
    from mrcomm.live.agent_run import run_agent
    from mrcomm.live.settings import BaseOptions, LiveSettings, check_agent_clock
    from mrcomm.world.scenario import load_scenario

    check_agent_clock(clock, "--clock")
    base_options = BaseOptions(base, ros_namespace, ros_frame, ros_qos)
    if base_options.kind == "nav2":
        from mrcomm.ros2.runtime import Nav2Names, need_ros2

        need_ros2("--base")
        Nav2Names.of(robot, ros_namespace, frame=ros_frame, qos=ros_qos)  # names checked
    scenario = load_scenario(run.scenario)
    check_agent_id(scenario, robot)
    security = net.security(robot, scenario)
    zenoh = net.options(security)
    world_options = net.world_options(world_connect, security) if world_connect else None
    settings = LiveSettings(
        run,
        zenoh,
        record_dir.expanduser(),
        world=world_options,
        lease=lease,
        join_timeout=join_timeout,
        agent_clock=clock,
        operator=operator,
        base=base_options,
        emulated=emulated,
        mission=mission,
    ).with_record_dir()
    warn_insecure(net.insecure)
    if console:
        raise typer.Exit(_operator_console(settings, robot, port))
    raise typer.Exit(run_agent(settings, robot))


def _operator_console(settings: Any, robot: str, port: int) -> int:
    """The operator's process with its console page (the page in the main thread, the
    process's loop in another)."""
    from mrcomm.agents.commands import OPERATOR_ID

    if robot != OPERATOR_ID:
        raise InputError("only the operator's process serves a console", field="--console")
    from mrcomm.cli.console_cmd import need_console_extra

    need_console_extra("--console")
    from mrcomm.console.guard import ConsoleGuard
    from mrcomm.console.live_session import LiveConsole
    from mrcomm.console.page import serve
    from mrcomm.live.agent import AgentProcess
    from mrcomm.live.journal import new_incarnation
    from mrcomm.live.settings import CONSOLE_TOKEN_ENV

    process = AgentProcess(settings, robot, new_incarnation(settings.record_dir, robot))
    host = process.operator
    assert host is not None
    counts = process.bus.endpoints[OPERATOR_ID].counts
    page = LiveConsole(host.operator, process.resources.scenario.grid, counts)
    host.on_step = page.on_step
    # Started by mrcomm live: its secret comes in the environment (it printed the URL).
    guard = ConsoleGuard(port, os.environ.get(CONSOLE_TOKEN_ENV) or None)
    typer.echo(f"console: {guard.url}", err=True)
    status = serve(page, guard, process.run)
    return 1 if status is None else status


def radio_packet_error(process: Any) -> Any:
    """With a network model that has a per-message channel (the radio): a packet's
    loss probability at a received power, for the kernel's drop rules (None with the
    other models)."""
    from mrcomm.live.kernel_links import PACKET_BYTES

    channel = process.links.network.channel(process.node_ids)
    if channel is None:
        return None
    bits = channel.bits_of(PACKET_BYTES)
    return lambda power: channel.mean_error(power, bits)
