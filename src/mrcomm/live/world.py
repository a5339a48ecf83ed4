"""The world process of live mode (``mrcomm world SCENARIO``; issue 7 §2).

Plays the role Stage plays for ROS robots with ``use_sim_time``: it simulates every
robot's base (:class:`~mrcomm.robot.base.SimBase`, the same as in simulation, with the
team's true positions for blocking and contact) and publishes the shared clock. Each
tick of ``dt`` simulated seconds, paced at ``speed`` times wall-clock time:

1. apply the base commands that arrived (in order, per robot and agent incarnation);
2. advance every base by ``dt``;
3. publish a :class:`~mrcomm.live.protocol.Tick`: the time and every base's state;
4. record ground truth (trajectories, separations, link summaries, distance, and the
   RSSI of every robot pair at 2 Hz where the threshold has one: ESD's trace, SSD's
   model); with ESD on the ``radio`` network model and no trace, also read every
   robot's pulse on the modelled radio and publish the readings on that robot's pulse
   key, so live ESD runs without hardware.

It starts once every team member reports ready with the same run configuration, and
ends the mission when every robot is done and the assigner has settled (after a short
grace for messages still in flight) or at the time limit, announcing the end until
the agents have gone. It is not a team member: a crash of any agent leaves it running.
"""

from __future__ import annotations

import secrets
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict
from typing import Protocol

import msgspec

from mrcomm.agents.assigner import ASSIGNER_ID
from mrcomm.errors import InputError
from mrcomm.live.agent import team_processes
from mrcomm.live.journal import Journal, journal_path, new_incarnation, track_presence
from mrcomm.live.kernel_links import KernelLinks
from mrcomm.live.protocol import (
    CH_AGENT_STATE,
    CH_BASE_CMD,
    CH_ROSTER,
    CH_TICK,
    WORLD_ID,
    AgentState,
    BaseCommand,
    BaseState,
    Roster,
    Tick,
    decoder_of,
    encoder,
)
from mrcomm.live.pulse import PublishingEndpoint
from mrcomm.live.settings import LiveSettings, config_crc, mission_bytes
from mrcomm.messaging.messages import TOPIC_RSSI, RssiMsg
from mrcomm.messaging.topics import Lane
from mrcomm.net.links import LinkState
from mrcomm.net.pulse import pulse_id
from mrcomm.net.zenoh_node import Incoming, ZenohNode
from mrcomm.ports import Base
from mrcomm.run.bodies import RobotBodies
from mrcomm.run.proximity import make_proximity
from mrcomm.run.resources import ScenarioResources
from mrcomm.run.wiring import (
    RadioPulse,
    make_bases,
    make_links,
    measures_radio,
    pulse_trace_path,
)
from mrcomm.world.geometry import Pose

END_GRACE_SIM = 1.0  # simulated s everyone must stay done before the mission ends ...
END_GRACE_WALL = 0.3  # ... and wall s, for messages still in flight
END_LINGER = 3.0  # wall s the end is announced while agents are still present


class BaseServer(Protocol):
    """Another way for agents to reach the simulated bases (``mrcomm world --ros2``:
    ``ros2.nav2_server``): goals taken before each step, state published after."""

    def apply(self, bases: Mapping[str, Base]) -> None: ...

    def publish(self, now: float, bases: Mapping[str, Base]) -> None: ...

    def summary(self) -> dict[str, object]:
        """What it served (recorded in the world's journal at the end)."""
        ...

    def close(self) -> None: ...


class WorldProcess:
    """Simulates the robots' bases and drives the shared clock."""

    def __init__(self, settings: LiveSettings, incarnation: int) -> None:
        self.settings = settings
        run = settings.run
        self.resources = ScenarioResources.load(run.scenario)
        scenario = self.resources.scenario
        self.robot_ids = tuple(r.id for r in scenario.robots)
        self.bodies = RobotBodies(
            make_bases(self.resources, run.seed, run.robot_variation()),
            self.resources.scenario.assigner,
        )
        self.bases = self.bodies.bases
        self.node_ids = (*self.robot_ids, ASSIGNER_ID)
        self.links, self.link_recorder = make_links(self.resources, run)
        self.proximity = make_proximity(run, self.robot_ids)
        #: ESD on the radio without hardware: the world reads every robot's pulse on the
        #: modelled radio and publishes the readings as that robot's pulse would.
        self.radio_pulse = (
            RadioPulse(self.links.network, self.robot_ids, self.robot_ids, run.seed)
            if measures_radio(run)
            else None
        )
        self.pulse_endpoints: dict[str, PublishingEndpoint] = {}
        self._pulse_seq = 0
        self.incarnation = incarnation
        self.team = team_processes(scenario)
        self.node = ZenohNode(settings.zenoh)
        # The mission's identity: every message of this run carries it.
        mission = settings.mission
        self.node.mission = mission_bytes(mission) if mission else secrets.token_bytes(8)
        self.journal = Journal(journal_path(settings.record_dir, WORLD_ID, incarnation))
        self._enc = encoder()
        self._applied: dict[str, tuple[int, int]] = {}  # robot -> (incarnation, seq)
        self.base_commands = 0  # base commands applied from agents over Zenoh
        self.states: dict[str, AgentState] = {}
        self.present: dict[str, set[int]] = {}
        #: ``present`` as joining agents are told it (replaced whole on every change:
        #: Zenoh's threads read it to answer their queries).
        self._roster = self._enc.encode(Roster({}))
        self.now = 0.0
        self._done_since: tuple[float, float] | None = None
        self.wall_start = 0.0
        self.wall_time = 0.0
        #: Called with the mission time, the robots' true poses and the link state of
        #: every tick (``mrcomm world --foxglove`` streams them to the Foxglove app).
        self.on_record: Callable[[float, dict[str, Pose], LinkState], None] | None = None
        #: The bases' ROS 2 face, when agents drive them through Nav2 (``--ros2``).
        self.base_server: BaseServer | None = None
        #: The model's links applied by the kernel to the agents' traffic (``--emulate``).
        self.kernel_links: KernelLinks | None = None

    # -- life cycle --------------------------------------------------------------------
    def run(self) -> int:
        prefix = self.node.prefix
        try:
            self.node.listen(f"{prefix}/*/{CH_BASE_CMD}", CH_BASE_CMD, decoder_of(BaseCommand))
            self.node.listen(f"{prefix}/*/{CH_AGENT_STATE}", CH_AGENT_STATE, decoder_of(AgentState))
            self.node.watch_presence()
            self.node.answer(self.node.key(WORLD_ID, CH_ROSTER), lambda: self._roster)
            self.node.prepare(self.node.key(WORLD_ID, CH_TICK), Lane.BEST_EFFORT)
            if self.radio_pulse is not None:
                self.pulse_endpoints = {
                    r: PublishingEndpoint(self.node, pulse_id(r), (TOPIC_RSSI,))
                    for r in self.robot_ids
                }
            self.node.declare_alive(WORLD_ID, self.incarnation)
            config = self.settings.run.model_dump(mode="json")
            # Collection may run elsewhere: name the scenario by its absolute path.
            config["scenario"] = str(self.settings.run.scenario.resolve())
            trace = pulse_trace_path(self.settings.run)
            if trace is not None:
                config["params"]["threshold"]["trace"] = str(trace.resolve())
            self.journal.start(
                process=WORLD_ID,
                incarnation=self.incarnation,
                config=config,
                speed=self.settings.speed,
                robots=list(self.robot_ids),
                listen=list(self.settings.zenoh.listen),
            )
            self._wait_for_team()
            end, timed_out = self._tick_loop()
            if self.kernel_links is not None:
                self.kernel_links.close(self.now)  # every link open for the last words
            self._announce_end(end, timed_out)
            self._write_truth(end, timed_out)
        finally:
            if self.base_server is not None:
                self.base_server.close()
            self.journal.close()
            self.node.close()
        return 0

    def _wait_for_team(self) -> None:
        deadline = time.monotonic() + self.settings.start_timeout
        crc = config_crc(self.settings.run)
        while True:
            ready = {a for a, s in self.states.items() if s.ready}
            covered = {h for a in ready for h in self.states[a].hosted}
            for agent in ready:
                if self.states[agent].config_crc != crc:
                    raise InputError(
                        f"{agent} runs a different run configuration than the world "
                        "(every process needs the same scenario and run options)",
                        field=agent,
                    )
            if set(self.team) <= covered:
                return
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                missing = sorted(set(self.team) - covered)
                raise InputError(
                    f"team not ready within {self.settings.start_timeout:g} s: "
                    f"missing {', '.join(missing)}",
                    field="--start-timeout",
                )
            if self.base_server is not None:
                # Robots report their pose before the mission, as real ones would.
                self.base_server.publish(0.0, self.bases)
            item = self.node.poll(min(remaining, 0.1))
            if item is not None:
                self._on_item(item)

    def _tick_loop(self) -> tuple[float, bool]:
        run = self.settings.run
        dt = run.dt
        period = dt / self.settings.speed
        self.wall_start = start = time.monotonic()
        self.journal.write("started", wall=time.time())
        k = 0
        self._publish_tick(Tick(0.0, self.settings.speed, self._base_states()))
        if self.base_server is not None:
            self.base_server.publish(0.0, self.bases)
        while True:
            self._drain(None)
            if self.base_server is not None:
                self.base_server.apply(self.bases)
            self._advance(dt)
            k += 1
            self.now = round(k * dt, 9)
            end = self._end_reached()
            timed_out = end is None and self.now >= run.max_time - 1e-9
            if end is not None or timed_out:
                self.wall_time = time.monotonic() - start
                return (end if end is not None else self.now), timed_out
            if self.base_server is not None:
                self.base_server.publish(self.now, self.bases)
            self._publish_tick(Tick(self.now, self.settings.speed, self._base_states()))
            self._record()
            target = start + k * period
            while True:
                remaining = target - time.monotonic()
                if remaining <= 0:
                    break
                self._drain(remaining)

    def _drain(self, wait: float | None) -> None:
        item = self.node.poll(wait)
        while item is not None:
            self._on_item(item)
            item = self.node.poll(None)

    def _on_item(self, item: Incoming) -> None:
        if item.channel == CH_BASE_CMD:
            self._apply(item.value)
        elif item.channel == CH_AGENT_STATE:
            state: AgentState = item.value
            self.states[state.agent] = state
        elif item.channel == "presence":
            track_presence(self.present, item.value, self.journal, self.now)
            live = {agent: tuple(sorted(i)) for agent, i in self.present.items() if i}
            self._roster = self._enc.encode(Roster(live))

    def _apply(self, command: BaseCommand) -> None:
        base = self.bases.get(command.robot)
        if base is None:
            return
        applied = self._applied.get(command.robot)
        if applied is not None and applied[0] == command.incarnation and command.seq <= applied[1]:
            return  # duplicate or stale
        self._applied[command.robot] = (command.incarnation, command.seq)
        self.base_commands += 1
        if command.kind == "goto":
            base.navigate_to(command.x, command.y)
        elif command.kind == "cancel":
            base.cancel()

    def _advance(self, dt: float) -> None:
        self.bodies.advance(dt, self.now, self.bodies.true_xy())

    def _base_states(self) -> tuple[BaseState, ...]:
        out = []
        for rid, base in self.bases.items():
            pose = base.pose
            inc, ack = self._applied.get(rid, (0, 0))
            out.append(
                BaseState(
                    rid,
                    base.status.value,
                    pose.x,
                    pose.y,
                    pose.theta,
                    base.odometry_distance,
                    base.speed,
                    inc,
                    ack,
                )
            )
        return tuple(out)

    def _publish_tick(self, tick: Tick) -> None:
        tick = msgspec.structs.replace(tick, mission=self.node.mission)
        self.node.put(self.node.key(WORLD_ID, CH_TICK), self._enc.encode(tick), Lane.BEST_EFFORT)

    # -- the end ---------------------------------------------------------------------------
    def _end_reached(self) -> float | None:
        """Time the team became done, once it has stayed done for the grace period."""
        done = self._team_done()
        if not done:
            self._done_since = None
            return None
        if self._done_since is None:
            self._done_since = (self.now, time.monotonic())
            return None
        since, wall = self._done_since
        if self.now - since >= END_GRACE_SIM and time.monotonic() - wall >= END_GRACE_WALL:
            return since
        return None

    def _team_done(self) -> bool:
        hosts: dict[str, AgentState] = {}
        for state in self.states.values():
            if state.incarnation not in self.present.get(state.agent, set()):
                continue  # a process that has gone
            for agent in state.hosted:
                hosts[agent] = state
        for robot in self.robot_ids:
            host = hosts.get(robot)
            if host is None or not host.done:
                return False
        assigner = hosts.get(ASSIGNER_ID)
        return assigner is not None and assigner.settled

    def _announce_end(self, end: float, timed_out: bool) -> None:
        tick = Tick(self.now, self.settings.speed, self._base_states(), True, end, timed_out)
        self.journal.write(
            "end",
            time=end,
            timed_out=timed_out,
            wall_time=self.wall_time,
            base_commands=self.base_commands,
        )
        if self.base_server is not None:
            self.journal.write("base_server", **self.base_server.summary())
        deadline = time.monotonic() + END_LINGER
        while time.monotonic() < deadline:
            self._publish_tick(tick)
            agents_left = any(self.present.get(a) for a in self.team)
            if not agents_left:
                return
            self._drain(0.1)

    # -- ground truth ------------------------------------------------------------------------
    def _record(self) -> None:
        positions = self.bodies.node_positions(self.bodies.true_xy())
        links = self.links.update(positions, self.now)
        if self.kernel_links is not None and self.kernel_links.due(self.now):
            self.kernel_links.update(links, self.now)
        if self.on_record is not None:
            self.on_record(self.now, {r: b.true_pose for r, b in self.bases.items()}, links)
        if self.radio_pulse is not None:
            self._publish_readings(self.radio_pulse.readings(self.now, links))
        # The RSSI of every robot pair at the pulse rate (the threshold's: ESD's trace,
        # SSD's model), as the simulation samples its ``rssi_series``.
        samples = self.link_recorder.record(links, self.settings.run.dt, self.now)
        if self.proximity is not None:
            self.proximity.record(links.distance, self.now)
        if samples:
            v = [[a, b, round(rssi, 3)] for a, b, rssi in samples]
            self.journal.write("rssi", t=round(self.now, 3), v=v)
        if self.bodies.sample_due(self.now):
            points = {rid: [x, y] for rid, (x, y) in self.bodies.sample().items()}
            self.journal.write("traj", t=round(self.now, 3), p=points)
            self.journal.write("clock", sim=self.now, wall=time.time())
            self.journal.flush()

    def _publish_readings(self, readings: list[tuple[str, str, float]]) -> None:
        for robot, peer, rssi in readings:
            self._pulse_seq += 1
            endpoint = self.pulse_endpoints[robot]
            message = RssiMsg(
                sender=endpoint.owner,
                incarnation=self.incarnation,
                seq=self._pulse_seq,
                stamp=self.now,
                robot=robot,
                peer=peer,
                rssi=rssi,
            )
            endpoint.publish(TOPIC_RSSI, message)

    def _write_truth(self, end: float, timed_out: bool) -> None:
        truth = {rid: asdict(t) for rid, t in self.bodies.truth(self.link_recorder).items()}
        for rid, (x, y) in self.bodies.sample().items():
            self.journal.write("traj", t=round(end, 3), p={rid: [x, y]})
        self.journal.write(
            "truth",
            end_time=end,
            timed_out=timed_out,
            wall_time=self.wall_time,
            robots=truth,
            links=self.link_recorder.summaries(),
            connectivity=self.link_recorder.connectivity(),
            link_states=self.link_recorder.state_intervals(end),
            encounters=self.proximity.encounters(end) if self.proximity else None,
        )


def run_world(settings: LiveSettings, incarnation: int | None = None) -> int:
    """Run the world process to the end of the mission; returns the exit status."""
    inc = incarnation if incarnation is not None else new_incarnation(settings.record_dir, WORLD_ID)
    return WorldProcess(settings, inc).run()
